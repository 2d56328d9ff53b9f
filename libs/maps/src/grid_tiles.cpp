#include "grid_tiles.h"

#include <zlib.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace upd::maps::detail {

namespace {

constexpr std::size_t kRecord = 7 * sizeof(float) + 4 * sizeof(std::uint32_t) + sizeof(double);
static_assert(kRecord == 52, "the packed cell record");

void pack(const GridCell& c, std::uint8_t* r) {
  const float f[7] = {c.logodds_nontrav, c.zeta_min,    c.zeta_mean,      c.slope_rad,
                      c.cost_mean,       c.elevation_m, c.elevation_max_m};
  const std::uint32_t u[4] = {c.hits, c.zeta_count, c.slope_count, c.cost_count};
  std::memcpy(r, f, sizeof f);
  std::memcpy(r + sizeof f, u, sizeof u);
  std::memcpy(r + sizeof f + sizeof u, &c.last_seen_s, sizeof c.last_seen_s);
}

void unpack(const std::uint8_t* r, GridCell& c) {
  float f[7];
  std::uint32_t u[4];
  std::memcpy(f, r, sizeof f);
  std::memcpy(u, r + sizeof f, sizeof u);
  std::memcpy(&c.last_seen_s, r + sizeof f + sizeof u, sizeof c.last_seen_s);
  c.logodds_nontrav = f[0], c.zeta_min = f[1], c.zeta_mean = f[2], c.slope_rad = f[3];
  c.cost_mean = f[4], c.elevation_m = f[5], c.elevation_max_m = f[6];
  c.hits = u[0], c.zeta_count = u[1], c.slope_count = u[2], c.cost_count = u[3];
}

}  // namespace

std::size_t GridTileStore::maxTileBytes(int tile_cells) {
  const auto raw = static_cast<uLong>(tile_cells) * static_cast<uLong>(tile_cells) * kRecord;
  return compressBound(raw) + kEntryBytes;
}

std::vector<GridCell> GridTileStore::load(const TileKey& key) const {
  const std::size_t cells = static_cast<std::size_t>(n_) * static_cast<std::size_t>(n_);
  std::vector<GridCell> out(cells);
  const auto it = tiles_.find(key);
  if (it == tiles_.end()) return out;
  std::vector<std::uint8_t> shuffled(cells * kRecord);
  uLongf size = static_cast<uLongf>(shuffled.size());
  if (uncompress(shuffled.data(), &size, it->second.data(), static_cast<uLong>(it->second.size())) !=
          Z_OK ||
      size != shuffled.size()) {
    throw std::logic_error("GridTileStore: tile " + std::to_string(key.first) + "," +
                           std::to_string(key.second) + " does not decompress");
  }
  std::uint8_t record[kRecord];
  for (std::size_t i = 0; i < cells; ++i) {
    for (std::size_t b = 0; b < kRecord; ++b) record[b] = shuffled[b * cells + i];
    unpack(record, out[i]);
  }
  return out;
}

void GridTileStore::store(const TileKey& key, const std::vector<GridCell>& cells) {
  bool observed = false;
  for (const GridCell& c : cells) observed = observed || c.observed();
  if (!observed) {
    erase(key);
    return;
  }
  const std::size_t n = cells.size();
  std::vector<std::uint8_t> shuffled(n * kRecord);
  std::uint8_t record[kRecord];
  for (std::size_t i = 0; i < n; ++i) {
    pack(cells[i], record);
    for (std::size_t b = 0; b < kRecord; ++b) shuffled[b * n + i] = record[b];
  }
  std::vector<std::uint8_t> packed(compressBound(static_cast<uLong>(shuffled.size())));
  uLongf size = static_cast<uLongf>(packed.size());
  if (compress2(packed.data(), &size, shuffled.data(), static_cast<uLong>(shuffled.size()),
                Z_BEST_SPEED) != Z_OK) {
    throw std::runtime_error("GridTileStore: zlib cannot compress a tile");
  }
  packed.resize(size);
  packed.shrink_to_fit();
  erase(key);
  bytes_ += packed.size();
  tiles_.emplace(key, std::move(packed));
}

const std::vector<std::uint8_t>* GridTileStore::packed(const TileKey& key) const {
  const auto it = tiles_.find(key);
  return it == tiles_.end() ? nullptr : &it->second;
}

void GridTileStore::putPacked(const TileKey& key, std::vector<std::uint8_t> bytes) {
  erase(key);
  bytes_ += bytes.size();
  tiles_.emplace(key, std::move(bytes));
}

void GridTileStore::erase(const TileKey& key) {
  const auto it = tiles_.find(key);
  if (it == tiles_.end()) return;
  bytes_ -= it->second.size();
  tiles_.erase(it);
}

}  // namespace upd::maps::detail
