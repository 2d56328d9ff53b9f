// The maps of a whole run in `upd playback`: what the working set (the grid's rolling window, the
// octree's update box) and the tiles kept from outside it held at the end of the run, and the
// switch to the whole run that every export then writes.
#pragma once

#include "upd/maps/traversability_grid.h"
#include "upd/maps/traversability_octree.h"

#include <nlohmann/json.hpp>

#include <cstddef>

namespace upd::app {

/// The process's peak resident memory so far (VmHWM of /proc/self/status) [bytes]; 0 when the
/// file cannot be read (not Linux).
std::size_t peakResidentBytes();

/// summary.json's "memory": the peak resident memory so far and the maps' own bytes (window or
/// box, kept tiles, the stated bound per grid tile).
nlohmann::json runMemoryJson(const maps::TraversabilityGrid& grid,
                             const maps::TraversabilityOcTree& tree);

/// Replaces the working maps by the whole run: the grid by one fixed window over every cell
/// observed, the tree gets every kept subtree back.
void switchToWholeRun(maps::TraversabilityGrid& grid, maps::TraversabilityOcTree& tree);

}  // namespace upd::app
