// Reading the input of `upd render` / `upd view` (view_input.h).
#include "view_input.h"

#include "map_folder.h"

#include "upd/io/cloud_io.h"
#include "upd/maps/traversability_octree.h"

#include <algorithm>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace upd::app {

namespace fs = std::filesystem;

bool isMapInput(const std::string& path) {
  return fs::is_directory(path) || io::lowerExtension(path) == ".ot";
}

namespace {

// The last frames/NNNNNN.ply of a folder (playback --ply), or "" when there is none.
std::string lastFramePly(const fs::path& dir) {
  std::vector<std::string> plys;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir / "frames", ec)) {
    if (e.path().extension() == ".ply") plys.push_back(e.path().string());
  }
  if (plys.empty()) return "";
  return *std::max_element(plys.begin(), plys.end());
}

ViewInput readFolder(const fs::path& dir) {
  ViewInput in;
  in.is_map = true;
  const MapFolder folder = readMapFolder(dir);
  nav::snapshotGrid(folder.grid, in.map);
  nav::snapshotOctree(*folder.tree, in.map, folder.grid.params().p_nontrav_threshold);
  if (fs::exists(dir / "map.3Dscene")) in.map.path = nav::readScenePath((dir / "map.3Dscene").string());
  in.cloud_file = lastFramePly(dir);
  if (!in.cloud_file.empty()) in.cloud = nav::loadScoredCloud(in.cloud_file);
  return in;
}

}  // namespace

ViewInput readViewInput(const std::string& path, const Eigen::Vector3f& up) {
  if (fs::is_directory(path)) return readFolder(path);
  ViewInput in;
  if (io::lowerExtension(path) == ".ot") {
    in.is_map = true;
    nav::snapshotOctree(*maps::readTraversabilityOt(path), in.map);
    if (in.map.voxels.empty()) throw std::runtime_error(path + ": the tree has no occupied voxel to draw");
    return in;
  }
  in.cloud = nav::loadScoredCloud(path, up);
  in.cloud_file = path;
  return in;
}

}  // namespace upd::app
