// Private to libs/maps: sets of OctoMap voxel keys for a frame's insert (octree_insert.cpp),
// without OctoMap's KeySet, which allocates a node for each key, and the sort of their Morton
// codes for the update of the inner nodes above them (traversability_octree.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include <octomap/OcTreeKey.h>  // (after <cstdint> and <vector>, which it uses unincluded)

namespace upd::maps::detail {

// The key packed in 48 bits: x | y << 16 | z << 32.
inline std::uint64_t packKey(const octomap::OcTreeKey& k) {
  return std::uint64_t{k[0]} | std::uint64_t{k[1]} << 16 | std::uint64_t{k[2]} << 32;
}

// A slot of a power-of-two table for a 64-bit code (Fibonacci hashing).
inline std::size_t hashSlot(std::uint64_t code, std::size_t table_size) {
  return static_cast<std::size_t>((code * 0x9E3779B97F4A7C15ull) >> 20) & (table_size - 1);
}

// A power-of-two table size of at least 64 and twice the entries expected (at most half full).
inline std::size_t tableSize(std::size_t expected) {
  std::size_t cap = 64;
  while (cap < 2 * expected) cap *= 2;
  return cap;
}

// A set of voxel keys: open addressing over the packed keys; keys() lists them in the order
// first added, and insert() gives a key's place in that list.
class FlatKeySet {
 public:
  void clear(std::size_t expected) {
    slots_.assign(tableSize(expected), Slot{});
    keys_.clear();
  }
  /// The key's index in keys(), and whether it was added now.
  std::pair<std::size_t, bool> insert(const octomap::OcTreeKey& k) {
    if (2 * (keys_.size() + 1) > slots_.size()) grow();
    return place(packKey(k), k);
  }
  const std::vector<octomap::OcTreeKey>& keys() const { return keys_; }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  struct Slot {
    std::uint64_t code = kEmpty;
    std::size_t index = 0;
  };
  std::pair<std::size_t, bool> place(std::uint64_t v, const octomap::OcTreeKey& k) {
    for (std::size_t i = hashSlot(v, slots_.size());; i = (i + 1) & (slots_.size() - 1)) {
      if (slots_[i].code == v) return {slots_[i].index, false};
      if (slots_[i].code == kEmpty) {
        slots_[i] = {v, keys_.size()};
        keys_.push_back(k);
        return {slots_[i].index, true};
      }
    }
  }
  void grow() {
    const std::vector<octomap::OcTreeKey> keys = std::move(keys_);
    clear(keys.size() + 1);
    for (const auto& k : keys) place(packKey(k), k);
  }
  std::vector<Slot> slots_;
  std::vector<octomap::OcTreeKey> keys_;
};

// The occupied and free voxels of a frame's rays, each listed once in the order first marked,
// a voxel marked occupied never listed free: a set of bricks of 4 x 4 x 4 voxels (open
// addressing over the bricks' codes) with a bit per voxel in each of two masks. A ray's
// consecutive voxels mostly share a brick, and the brick met last is found without a probe.
class VoxelMarks {
 public:
  void clear(std::size_t expected_bricks) {
    slots_.assign(tableSize(expected_bricks), Brick{});
    bricks_ = 0;
    last_ = kEmpty;
    occupied_.clear();
    free_.clear();
  }
  void markOccupied(const octomap::OcTreeKey& k) {
    std::uint64_t bit;
    Brick& b = brickOf(k, bit);
    if (b.occupied & bit) return;
    b.occupied |= bit;
    occupied_.push_back(k);
  }
  // Marks k free unless it is marked occupied (mark every occupied voxel first).
  void markFree(const octomap::OcTreeKey& k) {
    std::uint64_t bit;
    Brick& b = brickOf(k, bit);
    if ((b.occupied | b.free) & bit) return;
    b.free |= bit;
    free_.push_back(k);
  }
  const std::vector<octomap::OcTreeKey>& occupied() const { return occupied_; }
  const std::vector<octomap::OcTreeKey>& free() const { return free_; }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  struct Brick {
    std::uint64_t code = kEmpty;
    std::uint64_t occupied = 0, free = 0;  // bit x | y << 2 | z << 4 of the voxel in the brick
  };
  Brick& brickOf(const octomap::OcTreeKey& k, std::uint64_t& bit) {
    bit = std::uint64_t{1} << ((k[0] & 3u) | (k[1] & 3u) << 2 | (k[2] & 3u) << 4);
    const std::uint64_t code = packKey(k) >> 2 & 0x3FFF3FFF3FFFull;  // (each key over 4)
    if (code == last_) return slots_[last_slot_];
    if (2 * (bricks_ + 1) > slots_.size()) grow();
    std::size_t i = hashSlot(code, slots_.size());
    while (slots_[i].code != code && slots_[i].code != kEmpty) i = (i + 1) & (slots_.size() - 1);
    if (slots_[i].code == kEmpty) {
      slots_[i].code = code;
      ++bricks_;
    }
    last_ = code;
    last_slot_ = i;
    return slots_[i];
  }
  void grow() {
    std::vector<Brick> old(2 * slots_.size());
    old.swap(slots_);
    for (const Brick& b : old) {
      if (b.code == kEmpty) continue;
      std::size_t i = hashSlot(b.code, slots_.size());
      while (slots_[i].code != kEmpty) i = (i + 1) & (slots_.size() - 1);
      slots_[i] = b;
    }
    last_ = kEmpty;
  }
  std::vector<Brick> slots_;
  std::size_t bricks_ = 0;
  std::uint64_t last_ = kEmpty;
  std::size_t last_slot_ = 0;
  std::vector<octomap::OcTreeKey> occupied_, free_;
};

// Sorts codes of `bits` bits (std::sort's order): least significant digit first, 12 bits a
// digit, a digit every code shares skipped (a frame's voxels share their Morton codes' highest
// digits).
inline void radixSort(std::vector<std::uint64_t>& codes, std::vector<std::uint64_t>& buffer,
                      int bits) {
  constexpr int kBits = 12, kBins = 1 << kBits;
  const int digits = (bits + kBits - 1) / kBits;
  std::vector<std::uint32_t> counts(static_cast<std::size_t>(digits) * kBins, 0);
  for (const std::uint64_t c : codes) {
    for (int d = 0; d < digits; ++d) ++counts[d * kBins + ((c >> (d * kBits)) & (kBins - 1))];
  }
  buffer.resize(codes.size());
  for (int d = 0; d < digits; ++d) {
    std::uint32_t* count = counts.data() + d * kBins;
    const std::uint64_t first = codes.empty() ? 0 : (codes[0] >> (d * kBits)) & (kBins - 1);
    if (count[first] == codes.size()) continue;
    std::uint32_t offset = 0;
    for (int b = 0; b < kBins; ++b) offset += std::exchange(count[b], offset);
    for (const std::uint64_t c : codes) buffer[count[(c >> (d * kBits)) & (kBins - 1)]++] = c;
    codes.swap(buffer);
  }
}

}  // namespace upd::maps::detail
