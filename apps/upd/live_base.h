// The robot bases `upd live --base NAME` drives: "sim" (the simulated differential drive, the
// default: the loop owns it) or "ros" (ros1::RosRobotBase over /cmd_vel and /odom, built with
// ROS 1).
#pragma once

#include "upd/nav/robot_base.h"

#include <memory>
#include <string>

namespace upd::app {

/// nullptr for "sim"; the ROS base for "ros" (std::runtime_error when upd was built without
/// ROS 1, or no master or odometry answers); UsageError for another name.
std::unique_ptr<nav::RobotBase> makeLiveBase(const std::string& name);

}  // namespace upd::app
