// `upd live --view`: the viewer of `upd view` and `upd playback --view` (upd/nav/viewer.h)
// updated with every live frame: the frame's scored cloud, the grid as fused so far, the robot
// (its box at the base's pose), the path it drove and, when navigating, the route to the goal.
// The keys of the viewer work while the robot runs; `--screenshot` saves the last view.
#pragma once

#include "upd/core/frame_scorer.h"
#include "upd/maps/traversability_grid.h"
#include "upd/nav/robot_base.h"
#include "upd/nav/route_planner.h"
#include "upd/nav/viewer.h"
#include "upd/sim/robot.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace upd::app {

class LiveView {
 public:
  /// Opens the window; throws std::runtime_error without a display.
  LiveView(const std::string& title, const sim::RobotBodyParams& body);
  /// False once the user closed the window.
  bool isOpen() const { return viewer_.isOpen(); }
  /// Handles the keys pressed and redraws with this frame (route may be null).
  void show(const core::ScoredFrame& frame, const maps::TraversabilityGrid& grid,
            const nav::Pose2D& pose_world_robot, const nav::Route* route);
  /// Writes what the window shows to png (atomically); throws when no image comes.
  void saveScreenshot(const std::string& png) { viewer_.saveScreenshot(png); }

 private:
  nav::Viewer viewer_;
  sim::RobotBodyParams body_;
  std::vector<Eigen::Vector3f> path_;  ///< the poses shown so far [m, world]
};

}  // namespace upd::app
