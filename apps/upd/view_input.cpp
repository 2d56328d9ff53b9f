// Reading the input of `upd render` / `upd view` (view_input.h).
#include "view_input.h"

#include "map_folder.h"

#include "upd/io/cloud_io.h"
#include "upd/maps/grid_export.h"
#include "upd/maps/traversability_octree.h"

#include <octomap/ColorOcTree.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <vector>

namespace upd::app {

namespace fs = std::filesystem;

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

// map.ot, the ColorOcTree every OctoMap tool reads: its colour is the traversability colour of
// map.png (grey without evidence), so the label comes back from it; zeta and cost do not.
void snapshotColourOctree(const octomap::ColorOcTree& colour, nav::MapSnapshot& out,
                          double p_nontrav_threshold = 0.65) {
  for (auto it = colour.begin_leafs(), end = colour.end_leafs(); it != end; ++it) {
    if (!colour.isNodeOccupied(*it)) continue;
    nav::MapVoxelView v;
    v.centre = Eigen::Vector3f(float(it.getX()), float(it.getY()), float(it.getZ()));
    v.size = float(it.getSize());
    const octomap::ColorOcTreeNode::Color c = it->getColor();
    if (c.r != maps::kUnknownColourRgb[0] || c.g != maps::kUnknownColourRgb[1] || c.b != maps::kUnknownColourRgb[2]) {
      // Inverse of traversabilityColourRgb: red rises to 255 at p = 0.5, then green falls.
      const double p = c.r < 255 ? c.r / 510.0 : 1.0 - c.g / 510.0;
      v.label = p >= p_nontrav_threshold ? core::Label::NonTraversable : core::Label::Traversable;
    }
    out.voxels.push_back(v);
  }
}

}  // namespace

std::string firstColor(const ViewInput& in, const std::optional<std::string>& asked) {
  if (asked) return *asked;
  if (!in.is_map || in.cloud) return "zeta";
  const auto has = [](const auto& views) {
    return std::any_of(views.begin(), views.end(), [](const auto& v) { return std::isfinite(v.zeta); });
  };
  return has(in.map.cells) || has(in.map.voxels) ? "zeta" : "label";
}

ViewInput readViewInput(const std::string& path, const Eigen::Vector3f& up) {
  if (fs::is_directory(path)) return readFolder(path);
  ViewInput in;
  if (io::lowerExtension(path) == ".ot") {
    in.is_map = true;
    const maps::AnyOt tree = maps::readAnyOt(path);
    if (tree.colour) snapshotColourOctree(*tree.colour, in.map);
    else nav::snapshotOctree(*tree.traversability, in.map);
    if (in.map.voxels.empty()) throw std::runtime_error(path + ": the tree has no occupied voxel to draw");
    return in;
  }
  in.cloud = nav::loadScoredCloud(path, up);
  in.cloud_file = path;
  return in;
}

}  // namespace upd::app
