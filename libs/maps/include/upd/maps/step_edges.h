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
//
// Bumps (findBumps): a rock a few centimetres taller than the step limit but a smooth dome
// (radius 0.1-0.4 m) has no jump between cells and reads flat to the UPD at d_m = 0.2 m (zeta
// above 0.96 over its whole surface), yet the robot cannot climb it and its flanks are as much
// an obstacle as its top. A cell c stands out as a bump when its mean elevation lies more than
// bump_height_m above the ground around it: the plane fitted (least squares, once more on the
// cells within bump_fit_tolerance_m of the first fit) to the cells of the ring between
// bump_ring_inner_m and bump_ring_outer_m round c. The ring must be one plane: at least
// bump_min_inliers of its known cells within the tolerance (a ring across a platform's edge, a
// ramp's foot or a wall is two surfaces and decides nothing), so a plane of any slope and a large
// platform read no bump. The bump is then the cells connected to c, inside the ring's inner
// radius, whose elevation stands more than bump_edge_m above that plane; it must not reach the
// ring (a platform or a ramp seen in part, not a rock), and every cell of it must read smooth to
// the UPD (zeta_min >= bump_min_zeta: an edge the UPD sees, a tall rock's, a platform's, a
// wall's, is the UPD's to mark; a map the UPD never scored, the oracle's, has no bumps). Found,
// the cells whose centre lies within bump_border_m of one of its cells are marked too: its
// flanks down to its foot and the truth's 5 cm border beyond. With 10 cm cells, 0.1 m adds the
// four side neighbours of each cell, not the diagonal ones: their centres lie 14 cm out, up to
// 9 cm beyond the border, and narrow the passages beside the rock.
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
  bool bumps = false;                ///< true: the bump check (findBumps); off: NAVIGATION.md
  double bump_height_m = 0.05;       ///< a cell this far above the ring's plane is a bump [m]
  double bump_edge_m = 0.01;         ///< the bump's cells stand this much above the plane [m]
  double bump_ring_inner_m = 0.45;   ///< the ground ring round a cell: from (beyond a rock) [m]
  double bump_ring_outer_m = 0.65;   ///< ... to [m]
  double bump_fit_tolerance_m = 0.02;  ///< ring cells this close to the plane fit it [m]
  double bump_min_inliers = 0.75;    ///< share of the ring's known cells that must fit (0..1]
  double bump_min_zeta = 0.95;       ///< a bump's cells all have UPD zeta_min at least this
  double bump_border_m = 0.1;        ///< cells this near a bump's cell centre are marked [m]

  void validate() const;  ///< std::invalid_argument naming the field
  template <class V>
  void visit(V& v) {
    v("enabled", enabled, "mark step edges found on the grid's elevations as obstacles");
    v("max_step_m", max_step_m,
      "a height jump between neighbouring cells beyond the local slope taller than this is an "
      "obstacle [m]");
    v("min_hits", min_hits, "points a cell needs for its elevation to count (>= 1)");
    v("range_m", range_m, "cells within this distance of the robot are checked [m]");
    v("bumps", bumps, "mark bumps (rocks taller than bump_height_m above the ground round them)");
    v("bump_height_m", bump_height_m,
      "a cell this much higher than the plane of the ground ring round it is a bump [m]");
    v("bump_edge_m", bump_edge_m,
      "a bump's cells: connected to it, higher than this above the ring's plane [m]");
    v("bump_ring_inner_m", bump_ring_inner_m,
      "inner radius of the ground ring (beyond the largest rock) [m]");
    v("bump_ring_outer_m", bump_ring_outer_m, "outer radius of the ground ring [m]");
    v("bump_fit_tolerance_m", bump_fit_tolerance_m,
      "ring cells within this of the fitted plane are ground [m]");
    v("bump_min_inliers", bump_min_inliers,
      "share of the ring's known cells that must be ground, else no decision (0..1]");
    v("bump_min_zeta", bump_min_zeta,
      "a bump's cells all read smoother than this to the UPD (zeta_min); a rougher one is the "
      "UPD's to mark, a cell it never scored decides nothing [0, 1]");
    v("bump_border_m", bump_border_m,
      "cells whose centre lies within this of a bump cell's centre are marked too (0: the bump "
      "only) [m]");
  }
};

/// Centres (world xy) of the step-edge cells within range_m of centre_xy (see the header
/// comment); empty when disabled.
std::vector<Eigen::Vector2d> findStepEdges(const TraversabilityGrid& grid,
                                           const Eigen::Vector2d& centre_xy,
                                           const StepEdgeParams& params);

/// Centres (world xy) of the cells of bumps found at cells within range_m of centre_xy (see the
/// header comment), each once; empty when enabled or bumps is false.
std::vector<Eigen::Vector2d> findBumps(const TraversabilityGrid& grid,
                                       const Eigen::Vector2d& centre_xy,
                                       const StepEdgeParams& params);

}  // namespace upd::maps
