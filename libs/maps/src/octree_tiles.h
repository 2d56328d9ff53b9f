// The subtrees of the traversability tree that left its update box
// (OctreeParams::keep_outside_box): leaf records (key, depth, occupancy and traversability) in
// tiles of tile_voxels x tile_voxels voxels along x and y (every z), each tile's records
// zlib-compressed in memory. Records are appended as subtrees leave the box and taken back whole
// when the box returns over their tile, so a voxel is in the tree or in one tile, never both.
#pragma once

#include <cstddef>
#include <cstdint>

#include <map>
#include <utility>
#include <vector>

#include <octomap/OcTreeKey.h>  // needs <cstdint>, <cstddef> and <vector> first

namespace upd::maps {
class TraversabilityOcTreeNode;
}

namespace upd::maps::detail {

/// One kept leaf: where it is and what it holds (OctoMap's occupancy log-odds, then the
/// traversability fields of TraversabilityOcTreeNode).
struct LeafRecord {
  octomap::OcTreeKey key;  ///< the node's key as OctoMap's iterators give it
  std::uint8_t depth = 0;  ///< 16 for a voxel, less for a larger leaf
  float occupancy = 0, trav_logodds = 0, zeta_min = 0, cost_mean = 0;
  std::uint16_t observations = 0;
};

class OctreeTileStore {
 public:
  using TileKey = std::pair<int, int>;

  explicit OctreeTileStore(int tile_voxels);

  int tileVoxels() const { return 1 << shift_; }
  std::size_t tiles() const { return tiles_.size(); }
  std::size_t leaves() const { return leaves_; }
  /// Compressed bytes plus a fixed allowance per tile for its map entry.
  std::size_t bytes() const { return bytes_ + tiles_.size() * kEntryBytes; }

  /// The tile of a node whose lowest key is lo.
  TileKey tileOf(const octomap::OcTreeKey& lo) const { return {lo[0] >> shift_, lo[1] >> shift_}; }
  /// Whether tile t overlaps [min_key, max_key] along x and y.
  bool overlaps(const TileKey& t, const octomap::OcTreeKey& min_key,
                const octomap::OcTreeKey& max_key) const;

  /// Queues a record; flush() compresses what was queued into the tiles.
  void add(const TileKey& t, const LeafRecord& r);
  void flush();
  /// The tile's records, left in the store (load) or removed from it (take).
  std::vector<LeafRecord> load(const TileKey& t) const;
  std::vector<LeafRecord> take(const TileKey& t);
  std::vector<TileKey> keys() const;

 private:
  static constexpr std::size_t kEntryBytes = 96;  // std::map node + vector header, rounded up
  struct Tile {
    std::vector<std::uint8_t> packed;  // zlib of the records' bytes
    std::size_t records = 0;
  };
  int shift_;
  std::map<TileKey, Tile> tiles_;
  std::map<TileKey, std::vector<std::uint8_t>> pending_;  // raw records not yet compressed
  std::size_t bytes_ = 0, leaves_ = 0;
};

}  // namespace upd::maps::detail
