// Keeping the subtrees that leave the update box (octree_tiles.h) and putting them back.
#include "octree_tiles.h"

#include "upd/maps/traversability_octree.h"

#include <zlib.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace upd::maps {

namespace detail {

namespace {

constexpr std::size_t kRecord = 3 * sizeof(std::uint16_t) + 1 + 4 * sizeof(float) + sizeof(std::uint16_t);

void pack(const LeafRecord& r, std::uint8_t* out) {
  const std::uint16_t key[3] = {r.key[0], r.key[1], r.key[2]};
  const float f[4] = {r.occupancy, r.trav_logodds, r.zeta_min, r.cost_mean};
  std::memcpy(out, key, sizeof key);
  out[sizeof key] = r.depth;
  std::memcpy(out + sizeof key + 1, f, sizeof f);
  std::memcpy(out + sizeof key + 1 + sizeof f, &r.observations, sizeof r.observations);
}

LeafRecord unpack(const std::uint8_t* in) {
  std::uint16_t key[3];
  float f[4];
  LeafRecord r;
  std::memcpy(key, in, sizeof key);
  r.key = octomap::OcTreeKey(key[0], key[1], key[2]);
  r.depth = in[sizeof key];
  std::memcpy(f, in + sizeof key + 1, sizeof f);
  std::memcpy(&r.observations, in + sizeof key + 1 + sizeof f, sizeof r.observations);
  r.occupancy = f[0], r.trav_logodds = f[1], r.zeta_min = f[2], r.cost_mean = f[3];
  return r;
}

std::vector<std::uint8_t> inflate(const std::vector<std::uint8_t>& packed, std::size_t records) {
  std::vector<std::uint8_t> raw(records * kRecord);
  uLongf size = static_cast<uLongf>(raw.size());
  if (uncompress(raw.data(), &size, packed.data(), static_cast<uLong>(packed.size())) != Z_OK ||
      size != raw.size()) {
    throw std::logic_error("OctreeTileStore: a kept tile does not decompress");
  }
  return raw;
}

}  // namespace

OctreeTileStore::OctreeTileStore(int tile_voxels) : shift_(0) {
  while ((1 << shift_) < tile_voxels) ++shift_;
}

bool OctreeTileStore::overlaps(const TileKey& t, const octomap::OcTreeKey& min_key,
                               const octomap::OcTreeKey& max_key) const {
  const long size = 1L << shift_;
  const long x0 = static_cast<long>(t.first) * size, y0 = static_cast<long>(t.second) * size;
  return x0 + size - 1 >= min_key[0] && x0 <= max_key[0] && y0 + size - 1 >= min_key[1] &&
         y0 <= max_key[1];
}

void OctreeTileStore::add(const TileKey& t, const LeafRecord& r) {
  std::vector<std::uint8_t>& raw = pending_[t];
  raw.resize(raw.size() + kRecord);
  pack(r, raw.data() + raw.size() - kRecord);
}

void OctreeTileStore::flush() {
  for (auto& [key, added] : pending_) {
    Tile& tile = tiles_[key];
    std::vector<std::uint8_t> raw =
        tile.records > 0 ? inflate(tile.packed, tile.records) : std::vector<std::uint8_t>{};
    raw.insert(raw.end(), added.begin(), added.end());
    std::vector<std::uint8_t> packed(compressBound(static_cast<uLong>(raw.size())));
    uLongf size = static_cast<uLongf>(packed.size());
    if (compress2(packed.data(), &size, raw.data(), static_cast<uLong>(raw.size()),
                  Z_BEST_SPEED) != Z_OK) {
      throw std::runtime_error("OctreeTileStore: zlib cannot compress a tile");
    }
    packed.resize(size);
    packed.shrink_to_fit();
    bytes_ += packed.size();
    bytes_ -= tile.packed.size();
    leaves_ += added.size() / kRecord;
    tile.packed = std::move(packed);
    tile.records = raw.size() / kRecord;
  }
  pending_.clear();
}

std::vector<LeafRecord> OctreeTileStore::load(const TileKey& t) const {
  std::vector<LeafRecord> out;
  const auto it = tiles_.find(t);
  if (it == tiles_.end()) return out;
  const std::vector<std::uint8_t> raw = inflate(it->second.packed, it->second.records);
  out.reserve(it->second.records);
  for (std::size_t k = 0; k < it->second.records; ++k) out.push_back(unpack(raw.data() + k * kRecord));
  return out;
}

std::vector<LeafRecord> OctreeTileStore::take(const TileKey& t) {
  std::vector<LeafRecord> out = load(t);
  const auto it = tiles_.find(t);
  if (it != tiles_.end()) {
    bytes_ -= it->second.packed.size();
    leaves_ -= it->second.records;
    tiles_.erase(it);
  }
  return out;
}

std::vector<OctreeTileStore::TileKey> OctreeTileStore::keys() const {
  std::vector<TileKey> out;
  for (const auto& kv : tiles_) out.push_back(kv.first);
  return out;
}

}  // namespace detail

namespace {

detail::LeafRecord toRecord(const octomap::OcTreeKey& key, unsigned int depth,
                    const TraversabilityOcTreeNode& n) {
  detail::LeafRecord r;
  r.key = key;
  r.depth = static_cast<std::uint8_t>(depth);
  r.occupancy = n.getLogOdds();
  r.trav_logodds = n.getTraversabilityLogOdds();
  r.zeta_min = n.getZetaMin();
  r.cost_mean = n.getCostMean();
  r.observations = n.getObservations();
  return r;
}

TraversabilityOcTreeNode fromRecord(const detail::LeafRecord& r) {
  TraversabilityOcTreeNode n;
  n.setLogOdds(r.occupancy);
  n.setTraversability(r.trav_logodds, r.zeta_min, r.cost_mean, r.observations);
  return n;
}

}  // namespace

TraversabilityOcTree::~TraversabilityOcTree() = default;

template <class F>
void TraversabilityOcTree::forEachLeaf(const TraversabilityOcTreeNode* node,
                                       const octomap::OcTreeKey& key, unsigned int depth,
                                       F&& f) const {
  if (!nodeHasChildren(node)) {
    f(key, depth, *node);
    return;
  }
  const auto offset = static_cast<octomap::key_type>(tree_max_val >> (depth + 1));
  for (unsigned int i = 0; i < 8; ++i) {
    if (!nodeChildExists(node, i)) continue;
    octomap::OcTreeKey child_key;
    octomap::computeChildKey(i, offset, key, child_key);
    forEachLeaf(getNodeChild(node, i), child_key, depth + 1, f);
  }
}

void TraversabilityOcTree::keepSubtree(TraversabilityOcTreeNode* node,
                                       const octomap::OcTreeKey& key, unsigned int depth,
                                       detail::OctreeTileStore& keep) {
  const long half = depth < tree_depth ? static_cast<long>(tree_max_val >> depth) : 0;
  if (2 * half > keep.tileVoxels()) {
    // Larger than a tile: keep its children one by one (a leaf this large is split first).
    if (!nodeHasChildren(node)) expandNode(node);
    const auto offset = static_cast<octomap::key_type>(tree_max_val >> (depth + 1));
    for (unsigned int i = 0; i < 8; ++i) {
      if (!nodeChildExists(node, i)) continue;
      octomap::OcTreeKey child_key;
      octomap::computeChildKey(i, offset, key, child_key);
      keepSubtree(getNodeChild(node, i), child_key, depth + 1, keep);
    }
    return;
  }
  const octomap::OcTreeKey lo(static_cast<octomap::key_type>(key[0] - half),
                              static_cast<octomap::key_type>(key[1] - half),
                              static_cast<octomap::key_type>(key[2] - half));
  const detail::OctreeTileStore::TileKey tile = keep.tileOf(lo);
  forEachLeaf(node, key, depth,
              [&](const octomap::OcTreeKey& k, unsigned int d, const TraversabilityOcTreeNode& n) {
                keep.add(tile, toRecord(k, d, n));
              });
}

void TraversabilityOcTree::setNodeAt(const octomap::OcTreeKey& key, unsigned int depth,
                                     const TraversabilityOcTreeNode& data) {
  bool created = root == nullptr;
  if (created) {
    root = new TraversabilityOcTreeNode();
    ++tree_size;
    size_changed = true;
  }
  TraversabilityOcTreeNode* node = root;
  for (unsigned int d = 0; d < depth; ++d) {
    const unsigned int pos = octomap::computeChildIdx(key, static_cast<int>(tree_depth - 1 - d));
    if (!nodeChildExists(node, pos)) {
      // An existing leaf on the way holds the rest of its volume: split it rather than lose it.
      if (!created && !nodeHasChildren(node) && node != root) expandNode(node);
      if (!nodeChildExists(node, pos)) {
        createNodeChild(node, pos);
        created = true;
      }
    }
    node = getNodeChild(node, pos);
  }
  if (nodeHasChildren(node)) {
    for (unsigned int i = 0; i < 8; ++i) {
      if (nodeChildExists(node, i)) deleteNodeChild(node, i);
    }
  }
  node->copyData(data);
}

void TraversabilityOcTree::cropToKeyBoxKeeping(const octomap::OcTreeKey& min_key,
                                               const octomap::OcTreeKey& max_key,
                                               int tile_voxels) {
  if (!kept_) kept_ = std::make_unique<detail::OctreeTileStore>(tile_voxels);
  core::requireParam(kept_->tileVoxels() == tile_voxels, "TraversabilityOcTree", "tile_voxels",
                     tile_voxels, "differs from the tiles kept so far");
  if (root == nullptr) return;
  const octomap::OcTreeKey root_key(tree_max_val, tree_max_val, tree_max_val);
  const bool all_outside = cropRecurs(root, root_key, 0, min_key, max_key, kept_.get());
  kept_->flush();
  if (all_outside) {
    clear();
    return;
  }
  tree_size = calcNumNodes();
  size_changed = true;
  updateInnerOccupancy();
}

void TraversabilityOcTree::restoreKeptTiles(const octomap::OcTreeKey& min_key,
                                            const octomap::OcTreeKey& max_key) {
  if (!kept_) return;
  for (const auto& tile : kept_->keys()) {
    if (!kept_->overlaps(tile, min_key, max_key)) continue;
    for (const detail::LeafRecord& r : kept_->take(tile)) setNodeAt(r.key, r.depth, fromRecord(r));
  }
}

void TraversabilityOcTree::mergeKeptTiles() {
  if (!kept_) return;
  for (const auto& tile : kept_->keys()) {
    for (const detail::LeafRecord& r : kept_->take(tile)) setNodeAt(r.key, r.depth, fromRecord(r));
  }
  updateInnerOccupancy();
}

std::size_t TraversabilityOcTree::keptTiles() const { return kept_ ? kept_->tiles() : 0; }
std::size_t TraversabilityOcTree::keptLeaves() const { return kept_ ? kept_->leaves() : 0; }
std::size_t TraversabilityOcTree::keptTileBytes() const { return kept_ ? kept_->bytes() : 0; }

std::unique_ptr<TraversabilityOcTree> TraversabilityOcTree::wholeRun() const {
  auto out = std::make_unique<TraversabilityOcTree>(resolution);
  out->setProbHit(getProbHit());
  out->setProbMiss(getProbMiss());
  out->setClampingThresMin(getClampingThresMin());
  out->setClampingThresMax(getClampingThresMax());
  if (root != nullptr) {
    const octomap::OcTreeKey root_key(tree_max_val, tree_max_val, tree_max_val);
    forEachLeaf(root, root_key, 0,
                [&](const octomap::OcTreeKey& k, unsigned int d, const TraversabilityOcTreeNode& n) {
                  out->setNodeAt(k, d, n);
                });
  }
  if (kept_) {
    for (const auto& tile : kept_->keys()) {
      for (const detail::LeafRecord& r : kept_->load(tile)) out->setNodeAt(r.key, r.depth, fromRecord(r));
    }
  }
  out->updateInnerOccupancy();
  return out;
}

}  // namespace upd::maps
