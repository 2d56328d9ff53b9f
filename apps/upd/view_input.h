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

/// True when path is a directory or an .ot file (drawn as a map).
bool isMapInput(const std::string& path);

/// Reads path: a folder (map.tif, map_traversability.ot, map.3Dscene's path, the last
/// frames/*.ply when present), a traversability tree (.ot), or a cloud (scored with up when
/// raw). Throws std::runtime_error with one line naming the file on bad input.
ViewInput readViewInput(const std::string& path, const Eigen::Vector3f& up);

}  // namespace upd::app
