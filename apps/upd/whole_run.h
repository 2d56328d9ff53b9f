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
/// The process's resident memory now (VmRSS of /proc/self/status) [bytes]; 0 as above.
std::size_t residentBytes();

/// summary.json's "memory"."trace": every `every` frames processed, the resident memory and the
/// maps' own bytes then, to show that a long run's memory stays flat once the map's working set
/// (the grid's window, the octree's box, the tiles of the places seen) is reached.
class MemoryTrace {
 public:
  explicit MemoryTrace(std::size_t every = 1000) : every_(every) {}
  /// Records a sample when processed is a multiple of `every`.
  void frameProcessed(std::size_t processed, const maps::TraversabilityGrid& grid,
                      const maps::TraversabilityOcTree& tree);
  /// [{"frames", "rss_bytes", "grid_bytes", "octree_bytes"}, ...]
  const nlohmann::json& json() const { return samples_; }

 private:
  std::size_t every_;
  nlohmann::json samples_ = nlohmann::json::array();
};

/// summary.json's "memory": the peak resident memory so far and the maps' own bytes (window or
/// box, kept tiles, the stated bound per grid tile).
nlohmann::json runMemoryJson(const maps::TraversabilityGrid& grid,
                             const maps::TraversabilityOcTree& tree);

/// Replaces the working maps by the whole run: the grid by one fixed window over every cell
/// observed, the tree gets every kept subtree back.
void switchToWholeRun(maps::TraversabilityGrid& grid, maps::TraversabilityOcTree& tree);

}  // namespace upd::app
