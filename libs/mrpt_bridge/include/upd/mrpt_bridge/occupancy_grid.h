// The traversability grid as MRPT's occupancy grid, for MRPT's planners and navigators.
//
// Occupied means non-traversable: a known cell gets its fused probability of being
// non-traversable as occupancy, an unknown cell 0.5 (MRPT's "unobserved"). The MRPT grid has the
// same cell size and covers the same window; cell centres map one to one.
#pragma once

#include "upd/maps/traversability_grid.h"

#include <mrpt/maps/COccupancyGridMap2D.h>

namespace upd::mrpt_bridge {

mrpt::maps::COccupancyGridMap2D toOccupancyGrid(const maps::TraversabilityGrid& grid);

}  // namespace upd::mrpt_bridge
