#include "upd/nav/nav_interface.h"

#include <mrpt/kinematics/CVehicleVelCmd_DiffDriven.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/system/datetime.h>

#include <cmath>

namespace upd::nav {

UpdNavInterface::UpdNavInterface(RobotBase& base, const ObstacleSource& obstacles)
    : base_(base), obstacles_(obstacles), nav_time_start_s_(base.timeS()) {
  // MRPT logs every callback it does not see implemented; the library prints nothing.
  logging_enable_console_output = false;
  setMinLoggingLevel(mrpt::system::LVL_WARN);
}

bool UpdNavInterface::getCurrentPoseAndSpeeds(mrpt::math::TPose2D& cur_pose,
                                              mrpt::math::TTwist2D& cur_vel,
                                              mrpt::system::TTimeStamp& timestamp,
                                              mrpt::math::TPose2D& cur_odometry,
                                              std::string& frame_id) {
  BaseState s;
  if (!base_.readState(s)) return false;
  cur_pose = mrpt::math::TPose2D(s.pose_world_robot.x_m, s.pose_world_robot.y_m,
                                 s.pose_world_robot.yaw_rad);
  cur_odometry =
      mrpt::math::TPose2D(s.pose_odom_robot.x_m, s.pose_odom_robot.y_m, s.pose_odom_robot.yaw_rad);
  // MRPT wants the velocity in the world frame.
  const double c = std::cos(s.pose_world_robot.yaw_rad), sn = std::sin(s.pose_world_robot.yaw_rad);
  cur_vel = mrpt::math::TTwist2D(c * s.velocity.v_mps, sn * s.velocity.v_mps, s.velocity.w_radps);
  timestamp = mrpt::system::now();
  frame_id = "map";
  return true;
}

bool UpdNavInterface::changeSpeeds(const mrpt::kinematics::CVehicleVelCmd& vel_cmd) {
  const auto* cmd = dynamic_cast<const mrpt::kinematics::CVehicleVelCmd_DiffDriven*>(&vel_cmd);
  if (cmd == nullptr) return false;  // a PTG for another kinematic model: a config error
  return base_.sendVelocity({cmd->lin_vel, cmd->ang_vel});
}

bool UpdNavInterface::stop(bool is_emergency_stop) { return base_.stop(is_emergency_stop); }

mrpt::kinematics::CVehicleVelCmd::Ptr UpdNavInterface::getStopCmd() {
  auto cmd = std::make_shared<mrpt::kinematics::CVehicleVelCmd_DiffDriven>();
  cmd->setToStop();
  return cmd;
}

mrpt::kinematics::CVehicleVelCmd::Ptr UpdNavInterface::getEmergencyStopCmd() {
  return getStopCmd();
}

bool UpdNavInterface::senseObstacles(mrpt::maps::CSimplePointsMap& obstacles,
                                     mrpt::system::TTimeStamp& timestamp) {
  BaseState s;
  if (!base_.readState(s)) return false;
  const auto pts = obstacles_.pointsInRobot(s.pose_world_robot);
  const auto z = static_cast<float>(obstacles_.params().point_height_m);
  obstacles.clear();
  obstacles.reserve(pts.size());
  for (const auto& p : pts) {
    obstacles.insertPointFast(static_cast<float>(p.x()), static_cast<float>(p.y()), z);
  }
  obstacles.mark_as_modified();
  last_obstacle_count_ = pts.size();
  timestamp = mrpt::system::now();
  return true;
}

void UpdNavInterface::sendNavigationStartEvent() { ++events_.starts; }
void UpdNavInterface::sendNavigationEndEvent() { ++events_.ends; }
void UpdNavInterface::sendNavigationEndDueToErrorEvent() { ++events_.errors; }
void UpdNavInterface::sendWaySeemsBlockedEvent() { ++events_.way_seems_blocked; }
void UpdNavInterface::sendApparentCollisionEvent() { ++events_.apparent_collisions; }
void UpdNavInterface::sendCannotGetCloserToBlockedTargetEvent() { ++events_.blocked_target; }
void UpdNavInterface::sendWaypointReachedEvent(int /*waypoint_index*/, bool /*reached_nskipped*/) {}
void UpdNavInterface::sendNewWaypointTargetEvent(int /*waypoint_index*/) {}

double UpdNavInterface::getNavigationTime() { return base_.timeS() - nav_time_start_s_; }
void UpdNavInterface::resetNavigationTimer() { nav_time_start_s_ = base_.timeS(); }

}  // namespace upd::nav
