// `upd ros`: the ROS 1 node (libs/ros1, node.h). Built when ROS 1 was found (UPD_HAVE_ROS1);
// without it the command says so. ROS remapping arguments (from:=to, __name:=...) are passed
// to ros::init, as roslaunch gives them.
#include "cli.h"
#include "commands.h"
#include "nav_run_config.h"

#include "upd/nav/nav_config.h"

#ifdef UPD_HAVE_ROS1
#include "upd/ros1/node.h"
#endif

#include <cstdio>
#include <stdexcept>

namespace upd::app {

const char* const kRosUsage =
    "usage: upd ros [--config FILE.ini] [--nav-config FILE.ini] [--exit-after-goal]\n"
    "               [ROS remappings: from:=to, _param:=value, __name:=node]\n"
    "  A ROS 1 node (needs a running master: ROS_MASTER_URI). Subscribes to a depth image and\n"
    "  its CameraInfo (/camera/depth/image_raw, /camera/depth/camera_info) or a PointCloud2\n"
    "  (/points), takes the sensor and robot poses from tf (map or odom -> base_link -> the\n"
    "  message's frame), and publishes /upd/traversability (OccupancyGrid, latched: 0\n"
    "  traversable .. 100 non-traversable, -1 unknown), /upd/cloud (PointCloud2: x y z zeta\n"
    "  label cost) and /upd/route (MarkerArray). A goal on /move_base_simple/goal is driven to\n"
    "  with MRPT's reactive navigator: Twist on /cmd_vel, odometry from /odom. The goal\n"
    "  reached or failed, stale sensor data, a missing transform or a malformed message stop\n"
    "  the robot with one log line. Topic and frame names are private parameters\n"
    "  (docs/ROS.md); share/upd-nav/ros/upd.launch starts it, upd.rviz shows it.\n\n"
    "options:\n"
    "  --config FILE      robot config (default config/dune-kinect.ini)\n"
    "  --nav-config FILE  navigation config (default config/dune-nav.ini)\n"
    "  --exit-after-goal  exit when the first goal ends: status 0 reached, 3 failed\n";

#ifdef UPD_HAVE_ROS1

int runRos(const std::vector<std::string>& argv) {
  // ros::init takes out the remapping arguments; the rest are ours.
  std::vector<std::string> storage{"upd_ros"};
  storage.insert(storage.end(), argv.begin(), argv.end());
  std::vector<char*> cargs;
  for (auto& s : storage) cargs.push_back(s.data());
  int argc = static_cast<int>(cargs.size());
  ros::init(argc, cargs.data(), "upd");
  const std::vector<std::string> rest(cargs.begin() + 1, cargs.begin() + argc);

  const Args args(rest, {"--config", "--nav-config"}, {"--exit-after-goal"});
  if (!args.positionals().empty()) throw UsageError("unexpected argument " + args.positionals()[0]);
  const nav::NavConfig config = loadNavConfigs(navConfigPaths(args));

  if (!ros::master::check()) {
    throw std::runtime_error("no ROS master at " + ros::master::getURI() +
                             " (start roscore or set ROS_MASTER_URI)");
  }
  ros::NodeHandle nh;
  const ros1::RosNodeParams params = ros1::loadRosNodeParams(ros::NodeHandle("~"));
  ros1::TraversabilityNode node(nh, params, config);
  ROS_INFO("upd: listening on %s + %s and %s", params.depthImageTopic().c_str(),
           params.camera_info_topic.c_str(), params.points_topic.c_str());
  const ros1::NodeEnd end = node.spin(args.flag("--exit-after-goal"));
  std::printf("upd ros: %d frames, %s\n", node.framesProcessed(),
              end == ros1::NodeEnd::GoalReached  ? "goal reached"
              : end == ros1::NodeEnd::GoalFailed ? "goal failed"
                                                 : "shut down");
  return end == ros1::NodeEnd::GoalFailed ? 3 : 0;
}

#else

int runRos(const std::vector<std::string>&) {
  throw std::runtime_error(
      "upd was built without ROS 1 (install the packages scripts/setup.sh lists and rebuild)");
}

#endif

}  // namespace upd::app
