// Perception, mapping and navigation for one robot: what `upd navigate` (simulated camera and
// base) and `upd live` (a real depth camera, any RobotBase) both run.
//
// Per control step the caller
//  1. hands in the latest depth frame, already in the world frame (z up) at the base's current
//     pose: addFrame() scores it (upd::FrameScorer: UPD or roughness index), fuses it into the traversability grid,
//     adds the missing ground of its gaps (negative_obstacles.h) whose near side the map knows
//     as traversable and the step edges and bumps of the map's elevations near the robot
//     (upd/maps/step_edges.h) as NonTraversable evidence, and makes all these and the frame's
//     NonTraversable points the "current frame" obstacles;
//  2. calls step(): every replan_period_s the route planner searches the map for a route to the
//     goal and hands it to the navigator as waypoints; then the reactive navigator senses the
//     obstacles (map within range + current frame + fixed ones) in the robot frame and sends one
//     velocity command to the base;
//  3. lets the base move (a simulator advances its clock; a real robot just drives).
// When no route exists (the goal is walled in), the navigator keeps the last route it got (or,
// without any, the goal itself) and ends with its own error when it cannot get closer
// (NavigatorParams::no_progress_timeout_s). Replanning also stops when the route to the goal has
// not got shorter for that long: a robot circling a walled-in goal finds a new way in through
// every stretch of wall it has not seen yet, and would otherwise search until the time limit. A
// route that the map closed, replaced by another open way, counts as progress (the new way may
// be longer: round a wall whose gap is away from the goal). A robot that stays within
// RecoveryParams::stall_radius_m for stall_time_s while navigating is stalled: the loop drives one
// recovery manoeuvre (upd/nav/recovery.h) in place of the navigator, on ground the map has
// observed or the navigator's polygon has covered, then restarts the navigator on a fresh route.
// The navigator is created by the first navigateTo(), so a loop that only maps never builds PTGs.
#pragma once

#include "upd/maps/grid_fusion.h"
#include "upd/maps/traversability_grid.h"
#include "upd/nav/nav_config.h"
#include "upd/nav/navigator.h"
#include "upd/nav/obstacles.h"
#include "upd/nav/perception.h"
#include "upd/nav/recovery.h"
#include "upd/nav/robot_base.h"
#include "upd/nav/route_planner.h"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <unordered_set>
#include <vector>

namespace upd::nav {

/// The frame scorer's parameters for the loop: the robot config's pipeline and baseline, both
/// at PerceptionParams::upd_radius_m (when > 0), with the current frame's obstacle points.
core::FrameScorerParams loopScorerParams(const NavConfig& config, core::ObstacleDetector detector);

class NavigationLoop {
 public:
  /// base must outlive the loop. navlog_path: where the navigator writes its MRPT navlog
  /// (empty: none).
  NavigationLoop(RobotBase& base, const NavConfig& config, core::ObstacleDetector detector,
                 const std::string& navlog_path = "");
  ~NavigationLoop();
  NavigationLoop(const NavigationLoop&) = delete;
  NavigationLoop& operator=(const NavigationLoop&) = delete;

  /// Scores cloud_world (world frame, z up, sensor origin set; organized for the missing-ground
  /// check) with the loop's FrameScorer, reusing the last frame's buffers, and fuses it at
  /// time_s. ground_z_m: height of the ground under the robot (0 on flat
  /// ground), the level below which hidden ground counts as missing.
  const FrameEvidence& addFrame(const core::PointCloud& cloud_world, double time_s,
                                double ground_z_m = 0.0);
  /// Labels a frame's points by their world xy instead of the detector (the benchmark's oracle:
  /// the ground truth's traversability seen through the same camera). Empty: the detector.
  using PointLabeller = std::function<core::Label(double x_m, double y_m)>;
  void setLabeller(PointLabeller labeller) { labeller_ = std::move(labeller); }
  /// Obstacles known a priori (world frame), e.g. rectangleFence() of the mission area.
  void setFixedObstacles(std::vector<Eigen::Vector2d> points_world);

  /// Builds the navigator on first use, plans a route and starts navigating to goal_world.
  void navigateTo(const Eigen::Vector2d& goal_world);
  bool navigating() const;
  /// Replans when due, then one navigator step; requires navigateTo() first
  /// (std::logic_error otherwise).
  NavState step();
  /// The last route found (found = false before any).
  const Route& route() const { return route_; }
  /// Plans that found no route so far.
  int failedPlans() const { return failed_plans_; }
  /// True once replanning stopped for lack of progress (see the header comment).
  bool replanningStopped() const { return replanning_stopped_; }
  /// Recovery manoeuvres driven so far (see the header comment).
  int recoveries() const { return recoveries_; }
  NavOutcome outcome() const;
  /// Ends the navigation (stops the robot) and closes the navlog.
  void finish();

  const maps::TraversabilityGrid& grid() const { return grid_; }
  const ObstacleSource& obstacles() const { return obstacles_; }
  const FrameEvidence& lastFrame() const { return last_frame_; }
  const maps::GridFusionStats& lastFusion() const { return last_fusion_; }
  /// Missing-ground points (world xy) the last frame added as obstacles.
  const std::vector<Eigen::Vector2d>& lastMissingGround() const { return last_missing_ground_; }
  /// Step-edge and bump cells (world xy) the last frame added as obstacles
  /// (upd/maps/step_edges.h).
  const std::vector<Eigen::Vector2d>& lastStepEdges() const { return last_step_edges_; }
  /// The navigator (nullptr before navigateTo()).
  const Navigator* navigator() const { return navigator_.get(); }

 private:
  RobotBase& base_;
  NavConfig config_;
  core::FrameScorer scorer_;
  PointLabeller labeller_;
  std::string navlog_path_;
  maps::TraversabilityGrid grid_;
  ObstacleSource obstacles_;
  FrameEvidence last_frame_;
  maps::GridFusionStats last_fusion_;
  std::vector<Eigen::Vector2d> last_missing_ground_;
  std::vector<Eigen::Vector2d> last_step_edges_;
  std::unique_ptr<Navigator> navigator_;
  std::vector<Eigen::Vector2d> fixed_world_;
  Eigen::Vector2d goal_world_ = Eigen::Vector2d::Zero();
  Route route_;
  double last_plan_s_ = 0.0;
  int failed_plans_ = 0;
  bool replanning_stopped_ = false;
  double best_route_m_ = 0.0;     ///< shortest route length so far [m]
  double last_progress_s_ = 0.0;  ///< when the route last got shorter [s]
  Eigen::Vector2d stall_anchor_xy_ = Eigen::Vector2d::Zero();  ///< where the robot last stood [m]
  double stall_anchor_s_ = 0.0;   ///< since when it has stayed near stall_anchor_xy_ [s]
  int recoveries_ = 0;
  bool recovering_ = false;
  RecoveryMotion recovery_;
  double recovery_end_s_ = 0.0;
  /// Grid cells (world indices, packed) whose centres the navigator's polygon has covered: the
  /// robot stood there, so a recovery may drive there even when the camera never saw them.
  std::unordered_set<std::uint64_t> driven_cells_;

  void replan();
  /// The stall watch starts again from where the robot stands now.
  void restartStallWatch();
  /// True when the robot has stalled and a recovery manoeuvre was started.
  bool startRecoveryIfStalled();
  /// Adds the cells under the polygon (half sizes) at the pose to driven_cells_.
  void markDrivenCells(const Pose2D& pose_world_robot, double half_length_m, double half_width_m);
  /// The base's pose (std::runtime_error when it does not report one).
  Pose2D robotPose();
  /// Half length and half width of the navigator's polygon [m].
  Eigen::Vector2d polygonHalfSizes() const;
  /// Marks the ground under the robot as driven and hands the obstacle source the unobserved
  /// ground behind it (ObstacleParams::unobserved_behind_m).
  void updateDrivenAndUnobserved();
  /// The route's heading about 1 m ahead of the robot, in the robot frame [rad].
  double routeHeadingError(const Pose2D& pose_world_robot) const;
  void labelFrame(const core::PointCloud& cloud_world);
  /// Fuses the points (x, y, z) as NonTraversable evidence.
  void fuseNonTraversable(const std::vector<float>& x, const std::vector<float>& y,
                          const std::vector<float>& z, const Eigen::Vector2d& robot_xy,
                          double time_s);
};

}  // namespace upd::nav
