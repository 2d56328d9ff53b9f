// The 2.5D traversability map: a z-up world-frame grid of cells that hold fused per-point
// traversability evidence, over a bounded area.
//
// The grid is data only (like grid_map): named per-cell layers and coordinate conversions.
// Filling it is integrateScan() (grid_fusion.h), exporting it is grid_export.h and the MRPT
// bridge's occupancy_grid.h. Cells live in an mrpt::containers::CDynamicGrid (kept out of this
// header).
//
// Layers of a cell (GridCell, and GridLayer for named access). NaN means "never observed":
//  - logodds_nontrav: fused log-odds that the cell is non-traversable (rule in fusion.h);
//  - zeta_min: the smallest UPD zeta of any point ever seen in the cell;
//  - zeta_mean, slope_rad, cost_mean: means over every point with a finite value ever seen in
//    the cell (slope_rad is the MEAN slope of r, not the max);
//  - elevation_m: mean z of the cell's labelled points; elevation_max_m: their max z;
//  - hits: labelled (Traversable or NonTraversable) points ever integrated in the cell;
//  - last_seen_s: time of the last frame that updated the cell [s], in the caller's clock.
//
// Bounded memory: the window always has the same number of cells (extent_m / cell_size_m along
// x, extent_y_m / cell_size_m along y). With follow_robot the window is re-centred on the robot
// whenever the robot gets more than recenter_fraction of the extent from the window centre
// along x or y. With keep_outside_window (the default) the cells that scroll out are kept in
// compressed tiles of tile_cells x tile_cells cells and come back, bit for bit, when the window
// returns over them: a revisited area continues fusing onto its old evidence, and wholeRun()
// gives every cell ever observed as one fixed window. Memory is the window plus at most
// maxTileBytes() per stored tile (docs/MAPS.md gives measured sizes). Without it the cells that
// scroll out are dropped and cells that scroll in are unknown. Without follow_robot the window
// is fixed around (center_x_m, center_y_m) and points outside it are dropped (counted by
// integrateScan). Cell (i, j) covers
// [i * cell_size_m, (i + 1) * cell_size_m) x [j * cell_size_m, (j + 1) * cell_size_m) in the
// world, whatever the window: re-centring moves whole cells, never resamples.
#pragma once

#include "upd/core/params.h"
#include "upd/core/point_cloud.h"

#include <cmath>
#include <Eigen/Core>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>

namespace upd::maps {

/// Geometry of the grid and how its cells are read as labels. Loaded from [GridParams].
struct GridParams {
  double cell_size_m = 0.1;  ///< side of a cell [m/cell]
  double extent_m = 40.0;    ///< side of the window along x [m]; rounded to whole cells
  double extent_y_m = 0.0;   ///< side of the window along y [m]; 0: extent_m (a square)
  bool follow_robot = true;  ///< true: the window follows the robot; false: fixed window
  double center_x_m = 0.0;   ///< window centre [m, world]: fixed, or the initial one
  double center_y_m = 0.0;
  /// The window is re-centred on the robot when the robot is farther than this fraction of
  /// extent_m from its centre along x or y (0.25: at least a quarter extent ahead stays mapped).
  double recenter_fraction = 0.25;
  /// A known cell is non-traversable when its probability is >= this (ROS occupied_thresh).
  double p_nontrav_threshold = 0.65;
  int min_hits_known = 1;  ///< a cell with fewer hits is reported Unknown
  /// true: cells that leave the window are kept (compressed tiles) and come back when the
  /// window returns; false: they are dropped.
  bool keep_outside_window = true;
  int tile_cells = 64;  ///< side of a kept tile [cells] (8..1024)

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("cell_size_m", cell_size_m, "side of a grid cell [m]");
    v("extent_m", extent_m, "side of the map window along x [m] (memory bound)");
    v("extent_y_m", extent_y_m, "side of the map window along y [m]; 0: extent_m");
    v("follow_robot", follow_robot, "true: the window follows the robot; false: fixed window");
    v("center_x_m", center_x_m, "window centre x [m, world] (fixed, or initial)");
    v("center_y_m", center_y_m, "window centre y [m, world] (fixed, or initial)");
    v("recenter_fraction", recenter_fraction,
      "re-centre when the robot is this fraction of extent_m from the centre (0..0.5)");
    v("p_nontrav_threshold", p_nontrav_threshold,
      "probability at or above which a known cell is non-traversable (0..1)");
    v("min_hits_known", min_hits_known, "points a cell needs before it counts as known (>= 1)");
    v("keep_outside_window", keep_outside_window,
      "true: cells leaving the window are kept in compressed tiles and restored on return "
      "(whole-run maps); false: dropped");
    v("tile_cells", tile_cells, "side of a kept tile [cells] (8..1024)");
  }

  /// Cells of the window along x (cellsPerSide) and along y.
  int cellsPerSide() const;
  int cellsY() const;
};

/// One cell's layers (see the header comment). Default-constructed = never observed.
struct GridCell {
  static constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  float logodds_nontrav = kNaN;
  float zeta_min = kNaN;
  float zeta_mean = kNaN;
  float slope_rad = kNaN;
  float cost_mean = kNaN;
  float elevation_m = kNaN;
  float elevation_max_m = kNaN;
  std::uint32_t hits = 0;
  std::uint32_t zeta_count = 0;                                   ///< points behind zeta_mean
  std::uint32_t slope_count = 0;                                  ///< points behind slope_rad
  std::uint32_t cost_count = 0;                                   ///< points behind cost_mean
  double last_seen_s = std::numeric_limits<double>::quiet_NaN();  ///< double: epoch times

  bool observed() const { return hits > 0; }
};

/// Named access to the layers, for exports and matrices.
enum class GridLayer : int {
  ProbabilityNonTraversable = 0,  ///< from logodds_nontrav
  LogOddsNonTraversable,
  ZetaMin,
  ZetaMean,
  SlopeRad,
  CostMean,
  ElevationM,
  ElevationMaxM,
  Hits,
  LastSeenS,
};
constexpr int kGridLayerCount = 10;
const char* layerName(GridLayer layer);
/// The layer's value in the cell (hits as a float; NaN for a never-observed cell).
float layerValue(const GridCell& cell, GridLayer layer);

/// The window cell of a world point, for per-point loops: the arithmetic of
/// TraversabilityGrid::cellIndex, inline. Valid until the window moves.
struct GridCellIndexer {
  double inv_cell = 1.0;  ///< 1 / cell size [1/m]
  double i0 = 0, j0 = 0;  ///< world index of window cell (0, 0)
  double size_x = 0, size_y = 0;

  /// floor(x / cell) - i0 as floor(x * (1 / cell)) - i0; false outside the window or for NaN.
  bool operator()(double x_m, double y_m, int& cx, int& cy) const {
    const double gi = floorNoCall(x_m * inv_cell) - i0, gj = floorNoCall(y_m * inv_cell) - j0;
    if (!(gi >= 0 && gi < size_x && gj >= 0 && gj < size_y)) return false;
    cx = static_cast<int>(gi);
    cy = static_cast<int>(gj);
    return true;
  }
  /// std::floor without the library call baseline x86-64 makes of it (|v| < 2^52; others and
  /// NaN go to std::floor).
  static double floorNoCall(double v) {
    if (!(std::abs(v) < 4.5e15)) return std::floor(v);
    const auto t = static_cast<double>(static_cast<std::int64_t>(v));  // towards zero
    return v < t ? t - 1.0 : t;
  }
};

class TraversabilityGrid {
 public:
  /// Validates params (std::invalid_argument); every cell starts unknown.
  explicit TraversabilityGrid(const GridParams& params = {});
  ~TraversabilityGrid();
  TraversabilityGrid(const TraversabilityGrid& other);
  TraversabilityGrid& operator=(const TraversabilityGrid& other);
  TraversabilityGrid(TraversabilityGrid&&) noexcept;
  TraversabilityGrid& operator=(TraversabilityGrid&&) noexcept;

  const GridParams& params() const { return params_; }
  double cellSize() const { return params_.cell_size_m; }
  int sizeX() const;  ///< cells along x
  int sizeY() const;  ///< cells along y
  /// World index of the window's first cell: cell (cx, cy) is world cell (originI()+cx, ...).
  std::int64_t originI() const;
  std::int64_t originJ() const;
  double xMin() const;  ///< [m] window edges
  double yMin() const;
  double xMax() const;
  double yMax() const;

  /// Window indices of the cell holding (x_m, y_m); false when outside the window or not finite.
  bool cellIndex(double x_m, double y_m, int& cx, int& cy) const;
  /// The same computation, inline, for loops over many points.
  GridCellIndexer indexer() const;
  /// Centre of window cell (cx, cy) [m, world].
  Eigen::Vector2d cellCenter(int cx, int cy) const;

  /// Cell at window indices; no bounds check beyond an assert.
  const GridCell& at(int cx, int cy) const;
  GridCell& at(int cx, int cy);
  /// Cell holding (x_m, y_m), or nullptr outside the window.
  const GridCell* cellAt(double x_m, double y_m) const;
  GridCell* cellAt(double x_m, double y_m);

  /// Re-centres the window on robot_xy if follow_robot and the robot has left the central
  /// part (see the header comment). Returns true when the window moved.
  bool moveTo(const Eigen::Vector2d& robot_xy);
  /// Makes every cell unknown (the window stays where it is).
  void clear();

  /// Bytes held by the window and the kept tiles: windowBytes() + storedTileBytes().
  std::size_t memoryBytes() const;
  /// Bytes held by the window's cells (constant for a given GridParams).
  std::size_t windowBytes() const;
  /// Tiles kept of the cells outside the window (keep_outside_window), and their bytes.
  std::size_t storedTiles() const;
  std::size_t storedTileBytes() const;
  /// The stated bound on one kept tile: storedTileBytes() <= storedTiles() * maxTileBytes().
  std::size_t maxTileBytes() const;

  /// Every cell ever observed (the window and the kept tiles) as one fixed window
  /// (follow_robot and keep_outside_window off) over their bounding box, cells at their world
  /// indices; the window's own geometry, fixed, when nothing was observed.
  TraversabilityGrid wholeRun() const;

 private:
  friend struct GridStateAccess;  // grid_state.cpp: every cell to a file and back
  struct Impl;
  GridParams params_;
  std::unique_ptr<Impl> impl_;
};


/// Known = observed with at least min_hits_known hits.
bool isKnown(const GridCell& cell, const GridParams& params);
/// Unknown, NonTraversable (p >= p_nontrav_threshold) or Traversable.
core::Label labelOf(const GridCell& cell, const GridParams& params);
/// Probability of being non-traversable; NaN when unknown.
float probabilityOf(const GridCell& cell, const GridParams& params);

/// Queries at a world position; outside the window the cell is unknown.
float probabilityNonTraversable(const TraversabilityGrid& grid, double x_m, double y_m);
bool isKnown(const TraversabilityGrid& grid, double x_m, double y_m);
core::Label cellLabel(const TraversabilityGrid& grid, double x_m, double y_m);

/// A layer as a sizeY() x sizeX() matrix: entry (cy, cx) is cell (cx, cy), so row 0 is the
/// SOUTH edge (y min) as in CDynamicGrid::getAsMatrix. Unknown cells are NaN (Hits: 0).
Eigen::MatrixXf layerMatrix(const TraversabilityGrid& grid, GridLayer layer);

/// Calls f(cx, cy, cell) for every known cell, row by row from y min.
template <class F>
void forEachKnownCell(const TraversabilityGrid& grid, F&& f) {
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    for (int cx = 0; cx < grid.sizeX(); ++cx) {
      const GridCell& c = grid.at(cx, cy);
      if (isKnown(c, grid.params())) f(cx, cy, c);
    }
  }
}

struct GridStats {
  std::size_t cells = 0;  ///< cells in the window
  std::size_t known = 0;
  std::size_t traversable = 0;
  std::size_t non_traversable = 0;
  std::size_t memory_bytes = 0;
};
GridStats computeStats(const TraversabilityGrid& grid);

}  // namespace upd::maps
