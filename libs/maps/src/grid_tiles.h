// Cells of the 2.5D grid that left its window (GridParams::keep_outside_window): square tiles
// of tile_cells x tile_cells world cells, aligned on multiples of tile_cells in world cell
// indices, each kept zlib-compressed in memory. A tile is stored as the cells' 52-byte packed
// records, byte-shuffled (byte k of every record together: the NaN and zero runs of unobserved
// cells and the similar exponents of observed ones compress well), so a load returns the very
// bits that were stored.
#pragma once

#include "upd/maps/traversability_grid.h"

#include <cstddef>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

namespace upd::maps::detail {

using TileKey = std::pair<std::int64_t, std::int64_t>;  ///< (tx, ty): world cell tx * n ...

class GridTileStore {
 public:
  explicit GridTileStore(int tile_cells = 64) : n_(tile_cells) {}

  int tileCells() const { return n_; }
  std::size_t tiles() const { return tiles_.size(); }
  /// Compressed bytes plus a fixed allowance per tile for its map entry.
  std::size_t bytes() const { return bytes_ + tiles_.size() * kEntryBytes; }
  /// The most a tile can take in bytes() (zlib's bound on the raw records plus the allowance).
  static std::size_t maxTileBytes(int tile_cells);

  bool has(const TileKey& key) const { return tiles_.count(key) != 0; }
  /// The tile's cells, row-major from its south-west cell; all unknown when not stored.
  std::vector<GridCell> load(const TileKey& key) const;
  /// Stores the cells (n x n, row-major); erases the tile when none of them is observed.
  void store(const TileKey& key, const std::vector<GridCell>& cells);
  void erase(const TileKey& key);
  template <class F>
  void forEachKey(F&& f) const {
    for (const auto& kv : tiles_) f(kv.first);
  }
  /// The tile's compressed bytes as stored (nullptr: none), and storing such bytes back (a
  /// grid state file; load() checks them).
  const std::vector<std::uint8_t>* packed(const TileKey& key) const;
  void putPacked(const TileKey& key, std::vector<std::uint8_t> bytes);

 private:
  static constexpr std::size_t kEntryBytes = 96;  // std::map node + vector header, rounded up
  int n_;
  std::map<TileKey, std::vector<std::uint8_t>> tiles_;
  std::size_t bytes_ = 0;  // sum of the compressed sizes
};

/// floor(a / b) for b > 0.
inline std::int64_t floorDiv(std::int64_t a, std::int64_t b) {
  return a >= 0 ? a / b : -((-a + b - 1) / b);
}

}  // namespace upd::maps::detail

namespace upd::maps {

/// What the grid state file (grid_state.cpp) needs of the grid's insides
/// (traversability_grid.cpp).
struct GridStateAccess {
  /// Every observed cell as tiles: the kept ones with the window's cells written in.
  static detail::GridTileStore allCells(const TraversabilityGrid& grid);
  /// Places the window at world cell (i0, j0) and fills it and the kept tiles from `tiles`.
  static void restore(TraversabilityGrid& grid, std::int64_t i0, std::int64_t j0,
                      detail::GridTileStore tiles);
};

}  // namespace upd::maps
