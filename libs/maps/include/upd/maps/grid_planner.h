// The project's one grid planner: A* with clearance over a plain raster, used by the
// navigator's route planner (over the fused traversability grid) and by the simulated run
// (over the ground truth).
//
// The raster is a view of the caller's buffers (nothing is copied): square cells of cell_m,
// row-major from the lower-left cell (ix, iy) = (0, 0). A cell is
//  - blocked when the caller says so (an obstacle: never entered, and the clearance is
//    measured from it);
//  - impassable when its centre lies closer than inflation_m to a blocked cell's centre
//    (Euclidean, exact), unless the caller exempts it (e.g. around the robot, so a robot already
//    close to an obstacle can leave it);
//  - passable otherwise, at a cost per cell of 1 + clearance_weight (1 - d / clearance_m)^2
//    within clearance_m of a blocked cell (d its distance) plus the caller's extra cost, so
//    paths keep to the middle of passages.
// The search is 8-connected without corner cutting (a diagonal step needs both orthogonal
// neighbours passable); a step costs its length in cells times the mean cost of its two cells;
// the heuristic is the Euclidean distance in cells, admissible since every cost is >= 1.
#pragma once

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace upd::maps {

/// A raster for the planner, viewing the caller's buffers (width * height each, row-major
/// from the bottom row). Only blocked is required.
struct PlannerGridView {
  int width = 0, height = 0;                       ///< [cells]
  double cell_m = 0.1;                             ///< cell side [m/cell]
  const std::uint8_t* blocked = nullptr;           ///< non-zero: an obstacle cell
  const std::uint8_t* inflation_exempt = nullptr;  ///< non-zero: inflation ignored (optional)
  const double* extra_cost = nullptr;  ///< added to the cost of entering a cell, >= 0 (optional)

  std::size_t index(int ix, int iy) const { return static_cast<std::size_t>(iy) * width + ix; }
  bool inside(int ix, int iy) const { return ix >= 0 && iy >= 0 && ix < width && iy < height; }
};

struct GridPlannerParams {
  double inflation_m = 0.3;       ///< cells closer than this to a blocked cell are not entered [m]
  double clearance_m = 0.0;       ///< within this of a blocked cell the cost rises [m]; 0: never
  double clearance_weight = 0.0;  ///< extra cost per cell at a blocked cell's edge [-]

  void validate() const;  ///< std::invalid_argument naming the field
};

struct GridPlan {
  bool found = false;
  std::vector<Eigen::Vector2i> cells;  ///< from the start cell to the goal cell when found
  double cost = 0.0;                   ///< sum of the step costs [cells]
  /// Per cell, whether the search could enter it (also when nothing was found): for callers
  /// that check the start and goal or straighten the path (shortcutPath).
  std::vector<std::uint8_t> passable;
  /// Per cell, the distance to the nearest blocked cell centre [m], exact up to
  /// max(inflation_m, clearance_m); +inf farther.
  std::vector<float> distance_m;
};

/// Distance from every cell centre to the nearest blocked cell centre [m], up to reach_m
/// (farther cells: +inf). Throws std::invalid_argument for a view without blocked cells buffer.
std::vector<float> distanceToBlocked(const PlannerGridView& grid, double reach_m);

/// A* from start to goal (cells). Not found when either is outside the raster or impassable,
/// or no passable path joins them. Throws std::invalid_argument for bad params or view.
GridPlan planGridPath(const PlannerGridView& grid, const Eigen::Vector2i& start,
                      const Eigen::Vector2i& goal, const GridPlannerParams& params);

/// The polyline path_world (world positions; cell (ix, iy) of a position p is
/// floor((p - origin_xy) / cell_m)) with every point dropped that the points around it can do
/// without: from each kept point the farthest later one whose straight segment stays on
/// passable cells (sampled every quarter cell) is kept next, so a robot drives straight
/// segments instead of grid zig-zags. The first and last points are always kept.
std::vector<Eigen::Vector2d> shortcutPath(const PlannerGridView& grid,
                                          const std::vector<std::uint8_t>& passable,
                                          const Eigen::Vector2d& origin_xy,
                                          const std::vector<Eigen::Vector2d>& path_world);

}  // namespace upd::maps
