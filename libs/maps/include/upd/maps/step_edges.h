// Step edges on the fused 2.5D grid: cells where the ground height jumps by more than the
// robot can climb, found from the grid's per-cell mean elevation.
//
// The UPD at d_m = 0.5 m smooths an edge a few centimetres high over half a metre, so the edges
// of low steps and the sides of ramps near their foot read as traversable. The grid resolves
// them at its cell size: along x and along y through cell c (an edge of any direction crosses one
// of them at its full height; the diagonals' longer spacing would read 25 deg creases as 6.6 cm),
// with h(k) the mean elevation of the k-th cell from c along the direction, the ground on each
// side is extrapolated to c along the line through its two cells and
//   jump = | (2 h(+1) - h(+2)) - (2 h(-1) - h(-2)) |.
// A step edge inside c has level (or evenly sloping) ground on both sides: its jump is its
// height. A ramp's surface is continuous: on a plane the jump is 0 whatever the slope, and at
// its foot or top (a crease where the slope changes by tan a) at most one cell's rise,
// cell_size x tan a (4.7 cm for 25 deg at 0.1 m cells), below the limit for a drivable ramp. A
// cell is a step edge when the jump and the difference across it, |h(+1) - h(-1)|, both exceed
// max_step_m along x or y (the second keeps the cells whose outer neighbour straddles the
// edge out: an edge marks the cell holding it and one beside it); the four cells involved need
// min_hits points each (c itself need not be known).
#pragma once

#include "upd/core/params.h"
#include "upd/maps/traversability_grid.h"

#include <Eigen/Core>

#include <vector>

namespace upd::maps {

/// Loaded from [StepEdgeParams].
struct StepEdgeParams {
  bool enabled = true;        ///< false: no step-edge check
  double max_step_m = 0.05;   ///< taller jumps are obstacles (the robot's step limit) [m]
  int min_hits = 5;           ///< points a cell needs for its elevation to count
  double range_m = 2.5;       ///< cells within this of the robot are checked [m]

  void validate() const;  ///< std::invalid_argument naming the field
  template <class V>
  void visit(V& v) {
    v("enabled", enabled, "mark step edges found on the grid's elevations as obstacles");
    v("max_step_m", max_step_m,
      "a height jump between neighbouring cells beyond the local slope taller than this is an "
      "obstacle [m]");
    v("min_hits", min_hits, "points a cell needs for its elevation to count (>= 1)");
    v("range_m", range_m, "cells within this distance of the robot are checked [m]");
  }
};

/// Centres (world xy) of the step-edge cells within range_m of centre_xy (see the header
/// comment); empty when disabled.
std::vector<Eigen::Vector2d> findStepEdges(const TraversabilityGrid& grid,
                                           const Eigen::Vector2d& centre_xy,
                                           const StepEdgeParams& params);

}  // namespace upd::maps
