#include "whole_run.h"

#include <fstream>
#include <sstream>
#include <string>

namespace upd::app {

std::size_t peakResidentBytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) != 0) continue;
    std::istringstream in(line.substr(6));
    std::size_t kib = 0;
    in >> kib;
    return kib * 1024;
  }
  return 0;
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
