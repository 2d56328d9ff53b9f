#include "whole_run.h"

#include <fstream>
#include <sstream>
#include <string>

namespace upd::app {

namespace {

// A "Name:   N kB" line of /proc/self/status [bytes]; 0 when there is none.
std::size_t statusBytes(const std::string& name) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(name, 0) != 0) continue;
    std::istringstream in(line.substr(name.size()));
    std::size_t kib = 0;
    in >> kib;
    return kib * 1024;
  }
  return 0;
}

}  // namespace

std::size_t peakResidentBytes() { return statusBytes("VmHWM:"); }

std::size_t residentBytes() { return statusBytes("VmRSS:"); }

void MemoryTrace::frameProcessed(std::size_t processed, const maps::TraversabilityGrid& grid,
                                 const maps::TraversabilityOcTree& tree) {
  if (every_ == 0 || processed % every_ != 0) return;
  samples_.push_back({{"frames", processed},
                      {"rss_bytes", residentBytes()},
                      {"grid_bytes", grid.memoryBytes()},
                      {"octree_bytes", tree.memoryUsage() + tree.keptTileBytes()}});
}

nlohmann::json runMemoryJson(const maps::TraversabilityGrid& grid,
                             const maps::TraversabilityOcTree& tree) {
  return {{"vm_hwm_bytes", peakResidentBytes()},
          {"grid_window_bytes", grid.windowBytes()},
          {"grid_tiles", grid.storedTiles()},
          {"grid_tile_bytes", grid.storedTileBytes()},
          {"grid_max_bytes_per_tile", grid.maxTileBytes()},
          {"octree_box_bytes", tree.memoryUsage()},
          {"octree_tiles", tree.keptTiles()},
          {"octree_tile_leaves", tree.keptLeaves()},
          {"octree_tile_bytes", tree.keptTileBytes()}};
}

void switchToWholeRun(maps::TraversabilityGrid& grid, maps::TraversabilityOcTree& tree) {
  grid = grid.wholeRun();
  tree.mergeKeptTiles();
}

}  // namespace upd::app
