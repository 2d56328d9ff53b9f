// Fusing one frame of scored points into the 2.5D traversability grid.
//
// integrateScan() first moves the window (GridParams::follow_robot), then aggregates the frame's
// labelled points per cell and applies one log-odds update per cell (the rule in fusion.h), and
// updates the descriptor layers (zeta, slope, cost, elevation means, zeta_min, hits,
// last_seen_s) with every labelled point of the cell. Cells that the frame does not observe keep
// their values, so an obstacle that leaves the field of view stays in the map.
#pragma once

#include "upd/maps/fusion.h"
#include "upd/maps/traversability_grid.h"

#include <Eigen/Core>

#include <cstddef>

namespace upd::maps {

/// What one integrateScan() call did with its points (nothing is dropped silently).
struct GridFusionStats {
  std::size_t points_used = 0;       ///< labelled points inside the window
  std::size_t points_unknown = 0;    ///< Unknown label: ignored
  std::size_t points_invalid = 0;    ///< non-finite coordinates: ignored
  std::size_t points_outside = 0;    ///< labelled but outside the window: dropped
  std::size_t cells_updated = 0;     ///< cells that got a log-odds update
  std::size_t cells_hit = 0;         ///< ... of which seen as non-traversable
  std::size_t cells_too_sparse = 0;  ///< cells with fewer than min_points_per_cell points
  bool window_moved = false;
};

/// Integrates one frame; time_s is stored as the cells' last_seen_s. Throws
/// std::invalid_argument for bad params or an invalid view.
GridFusionStats integrateScan(TraversabilityGrid& grid, const PointsWorld& points,
                              const Eigen::Vector2d& robot_xy, double time_s,
                              const FusionParams& params);

}  // namespace upd::maps
