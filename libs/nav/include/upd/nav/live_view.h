// The 3D view of `upd live --view`: the latest cloud coloured by the UPD's zeta, the fused map
// (cell centres at their elevation, coloured by the probability of being non-traversable), the
// robot's footprint and the route. An MRPT CDisplayWindow3D, kept out of this header.
#pragma once

#include "upd/maps/traversability_grid.h"
#include "upd/nav/perception.h"
#include "upd/nav/robot_base.h"
#include "upd/nav/route_planner.h"
#include "upd/sim/robot.h"

#include <memory>
#include <string>

namespace upd::nav {

/// True when a window can be opened ($DISPLAY or $WAYLAND_DISPLAY is set).
bool displayAvailable();

class LiveView {
 public:
  /// Opens the window; throws std::runtime_error when there is no display.
  LiveView(const std::string& title, const sim::RobotBodyParams& body);
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// False once the user closed the window.
  bool isOpen() const;
  /// Redraws everything (route may be null).
  void update(const FrameEvidence& frame, const maps::TraversabilityGrid& grid,
              const Pose2D& pose_world_robot, const Route* route);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace upd::nav
