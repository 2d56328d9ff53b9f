// What `upd render` and `upd view` draw, read from their input: a scored PLY or raw cloud, an
// OctoMap tree (.ot) or a playback output folder (its map, path and last scored frame).
#pragma once

#include "upd/nav/figure.h"
#include "upd/nav/map_view.h"

#include <Eigen/Core>

#include <optional>
#include <string>

namespace upd::app {

struct ViewInput {
  nav::MapSnapshot map;                  ///< empty for a cloud
  std::optional<nav::ScoredCloud> cloud; ///< the cloud, or a folder's last frames/NNNNNN.ply
  std::string cloud_file;                ///< where the cloud came from (empty: none)
  bool is_map = false;                   ///< a folder or a tree: drawn in the world frame, z up
};

/// The map style to draw first: the asked one, but a tree's voxels when there is no grid.
inline nav::MapStyle firstMapStyle(const ViewInput& in, nav::MapStyle asked) {
  return asked == nav::MapStyle::Grid && !in.map.hasGrid() ? nav::MapStyle::Octree : asked;
}

/// The colouring to draw first: the asked one, else zeta, but the labels for a map that holds
/// no zeta (map.ot, the ColorOcTree, keeps only the labels' colours: by zeta it is all grey).
std::string firstColor(const ViewInput& in, const std::optional<std::string>& asked);

/// Reads path: a folder (map.tif, map_traversability.ot, map.3Dscene's path, the last
/// frames/*.ply when present), a tree (.ot: map_traversability.ot, or map.ot, the ColorOcTree,
/// whose colours give the labels only), or a cloud (scored with up when
/// raw). Throws std::runtime_error with one line naming the file on bad input.
ViewInput readViewInput(const std::string& path, const Eigen::Vector3f& up);

}  // namespace upd::app
