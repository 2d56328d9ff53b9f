// `upd playback --view`: the viewer (upd/nav/viewer.h) updated with every frame played: the
// frame's scored cloud, the grid (or the tree's voxels) as fused so far, the robot and its path.
#pragma once

#include "upd/core/frame_scorer.h"
#include "upd/maps/traversability_grid.h"
#include "upd/maps/traversability_octree.h"
#include "upd/nav/viewer.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace upd::app {

class PlaybackView {
 public:
  /// Opens the window; throws std::runtime_error without a display.
  explicit PlaybackView(const std::string& rawlog);
  /// Draws the frame and the maps, handles the keys pressed (nothing once the window is closed).
  void show(const core::ScoredFrame& frame, const maps::TraversabilityGrid& grid,
            const maps::TraversabilityOcTree& tree, const std::vector<Eigen::Vector3d>& trajectory);
  /// Keeps the window until the user closes it (a line on stdout says so).
  void waitUntilClosed();

 private:
  nav::Viewer viewer_;
};

}  // namespace upd::app
