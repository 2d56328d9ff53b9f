// MRPT's reactive navigator (CReactiveNavigationSystem: PTGs + a holonomic method in TP-space,
// Blanco et al. 2008) driving a RobotBase around the obstacles of an ObstacleSource, behind a
// header free of MRPT types.
//
// The navigator reads everything it needs from an MRPT ini file (the PTG file, e.g.
// config/ptg-dune.ini): the PTGs, the robot's 2D shape ([CReactiveNavigationSystem]
// RobotModel_shape2D_xs/ys), speed limits and the holonomic method. The PTGs' collision grids
// are cached as ReacNavGrid_*.dat.gz in ptg_cache_dir (never the working directory). With a
// navlog path it records an MRPT navigation log (CLogFileRecord per step) that
// `navlog-viewer` opens.
#pragma once

#include "upd/nav/obstacles.h"
#include "upd/nav/robot_base.h"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace upd::nav {

/// How the navigator's run ended (MRPT's CAbstractNavigator::TState).
enum class NavState { Idle, Navigating, Suspended, Error };
const char* toString(NavState s);

/// Loaded from [NavigatorParams]; the two paths are read as strings from the same section.
struct NavigatorParams {
  double target_allowed_distance_m = 0.3;  ///< the goal counts as reached within this [m]
  /// The navigator gives up (NAV_ERROR "cannot reach target") after this long without getting
  /// closer to the target; overrides the PTG file's alarm_seems_not_approaching_target_timeout.
  double no_progress_timeout_s = 30.0;
  double waypoint_allowed_distance_m = 0.6;  ///< an intermediate waypoint is reached within [m]
  /// The navigator may skip an intermediate waypoint when a later one is directly reachable
  /// (MRPT's allow_skip): a waypoint next to an obstacle mapped after the route was planned
  /// then cannot hold the robot until no_progress_timeout_s ends the run.
  bool skip_waypoints = true;

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("target_allowed_distance_m", target_allowed_distance_m,
      "the goal is reached within this distance [m]");
    v("no_progress_timeout_s", no_progress_timeout_s,
      "end with an error after this long without getting closer to the goal [s]");
    v("waypoint_allowed_distance_m", waypoint_allowed_distance_m,
      "an intermediate waypoint of a route is reached within this distance [m]");
    v("skip_waypoints", skip_waypoints,
      "the navigator may skip an intermediate waypoint when a later one is directly reachable");
  }
};

struct NavigatorSetup {
  std::string ptg_ini_path;   ///< MRPT ini with the navigator's sections (required)
  std::string ptg_cache_dir;  ///< collision-grid cache directory, created if missing (required)
  std::string navlog_path;    ///< where to write the .reactivenavlog; empty: no log
  NavigatorParams params;
};

/// The navigator's end: state and, on error, MRPT's reason.
struct NavOutcome {
  NavState state = NavState::Idle;
  bool target_reached = false;  ///< the navigator reported reaching the target
  std::string error_code;       ///< "ERR_CANNOT_REACH_TARGET", ...; empty without error
  std::string error_message;
};

class Navigator {
 public:
  /// Loads the PTG file (std::runtime_error naming it when missing or invalid) and builds the
  /// PTGs (loading or writing the cache). base and obstacles must outlive the navigator.
  Navigator(RobotBase& base, const ObstacleSource& obstacles, const NavigatorSetup& setup);
  ~Navigator();
  Navigator(const Navigator&) = delete;
  Navigator& operator=(const Navigator&) = delete;

  /// Starts navigating to goal_world (world frame, x y [m]); cancels any previous goal. The
  /// goal must lie within the PTGs' reach (about their refDistance) or the navigator finds no
  /// way; farther goals go through followWaypoints().
  void navigateTo(const Eigen::Vector2d& goal_world);
  /// Follows waypoints (world frame; the last one is the goal, reached within
  /// target_allowed_distance_m, the others within waypoint_allowed_distance_m, in order: MRPT's
  /// CWaypointsNavigator, with skipping disabled because a straight shot at a later waypoint
  /// cuts the corner the route went round). Cancels any previous goal.
  void followWaypoints(const std::vector<Eigen::Vector2d>& waypoints_world);
  /// One control step: senses obstacles, picks a motion, sends the velocity command.
  NavState step();
  NavState state() const;
  NavOutcome outcome() const;
  /// Stops the robot and ends the current navigation (state Idle, not reached).
  void cancel();

  /// The 2D robot shape of the PTG file (robot frame, polygon vertices) [m].
  std::vector<Eigen::Vector2d> robotShape() const;
  /// Obstacle points handed to the navigator at the last step.
  std::size_t lastObstacleCount() const;
  /// Closes the navlog (it is complete on disk afterwards). Also done by the destructor.
  void closeLog();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace upd::nav
