// The bridge between MRPT's reactive navigator and UPD-Nav: a CRobot2NavInterface over any
// RobotBase whose senseObstacles() returns the UPD's non-traversable evidence (ObstacleSource)
// in the robot frame.
//
// This is the one header of the library that exposes MRPT types (it must derive from MRPT's
// class); Navigator (navigator.h) wraps it for callers that do not want MRPT headers.
// Velocity commands are CVehicleVelCmd_DiffDriven (v [m/s], w [rad/s]); timestamps come from
// mrpt::Clock (the simulated clock in `upd navigate`, the wall clock in `upd live`); navigation
// time is the base's timeS().
#pragma once

#include "upd/nav/obstacles.h"
#include "upd/nav/robot_base.h"

#include <mrpt/nav/reactive/CRobot2NavInterface.h>

#include <string>
#include <vector>

namespace upd::nav {

/// Navigation events the navigator reported, in order (for logs and results).
struct NavEvents {
  int starts = 0;
  int ends = 0;    ///< target reached
  int errors = 0;  ///< communication errors with the base
  int way_seems_blocked = 0;
  int apparent_collisions = 0;
  int blocked_target = 0;  ///< target inside an obstacle
};

class UpdNavInterface : public mrpt::nav::CRobot2NavInterface {
 public:
  /// base and obstacles must outlive the interface.
  UpdNavInterface(RobotBase& base, const ObstacleSource& obstacles);

  bool getCurrentPoseAndSpeeds(mrpt::math::TPose2D& cur_pose, mrpt::math::TTwist2D& cur_vel,
                               mrpt::system::TTimeStamp& timestamp,
                               mrpt::math::TPose2D& cur_odometry, std::string& frame_id) override;
  bool changeSpeeds(const mrpt::kinematics::CVehicleVelCmd& vel_cmd) override;
  bool stop(bool is_emergency_stop) override;
  mrpt::kinematics::CVehicleVelCmd::Ptr getEmergencyStopCmd() override;
  mrpt::kinematics::CVehicleVelCmd::Ptr getStopCmd() override;
  /// The ObstacleSource's points around the current pose, in the robot frame, at z =
  /// ObstacleParams::point_height_m. False when the base cannot report its pose.
  bool senseObstacles(mrpt::maps::CSimplePointsMap& obstacles,
                      mrpt::system::TTimeStamp& timestamp) override;

  void sendNavigationStartEvent() override;
  void sendNavigationEndEvent() override;
  void sendNavigationEndDueToErrorEvent() override;
  void sendWaySeemsBlockedEvent() override;
  void sendApparentCollisionEvent() override;
  void sendCannotGetCloserToBlockedTargetEvent() override;
  void sendWaypointReachedEvent(int waypoint_index, bool reached_nskipped) override;
  void sendNewWaypointTargetEvent(int waypoint_index) override;

  double getNavigationTime() override;
  void resetNavigationTimer() override;

  const NavEvents& events() const { return events_; }
  /// Obstacle points handed to the navigator at the last senseObstacles().
  std::size_t lastObstacleCount() const { return last_obstacle_count_; }

 private:
  RobotBase& base_;
  const ObstacleSource& obstacles_;
  NavEvents events_;
  double nav_time_start_s_ = 0.0;
  std::size_t last_obstacle_count_ = 0;
};

}  // namespace upd::nav
