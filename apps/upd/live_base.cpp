#include "live_base.h"

#include "cli.h"

#ifdef UPD_HAVE_ROS1
#include "upd/ros1/ros_base.h"
#endif

#include <stdexcept>

namespace upd::app {

std::unique_ptr<nav::RobotBase> makeLiveBase(const std::string& name) {
  if (name == "sim") return nullptr;
  if (name != "ros") throw UsageError("option --base = '" + name + "': expected sim or ros");
#ifdef UPD_HAVE_ROS1
  return ros1::makeRosBase();  // /cmd_vel out, /odom in; waits for the first odometry
#else
  throw std::runtime_error("--base ros: upd was built without ROS 1 (install the packages "
                           "scripts/setup.sh lists and rebuild)");
#endif
}

}  // namespace upd::app
