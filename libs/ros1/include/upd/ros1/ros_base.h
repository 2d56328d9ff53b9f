// A RobotBase (upd/nav/robot_base.h) over the two topics every ROS base driver offers: velocity
// commands out (geometry_msgs/Twist on /cmd_vel), odometry in (nav_msgs/Odometry on /odom).
// The navigation loop then drives a real robot exactly as it drives the simulated one.
//
// The pose in the world is the odometry's, or, when a tf buffer is given and it holds
// world_frame -> base_frame, that transform (a localization on top of odometry). Odometry
// older than odom_timeout_s makes readState() fail: the navigator then stops the robot.
// Odometry is received on the base's own callback queue and spinner thread, so it stays fresh
// while the caller's thread scores a frame or builds the navigator; the state is guarded by a
// mutex.
#pragma once

#include "upd/nav/robot_base.h"

#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <nav_msgs/Odometry.h>
#include <tf2_ros/buffer.h>

#include <memory>
#include <mutex>
#include <string>

namespace upd::ros1 {

/// Topics and frames of the base. ROS parameters of the same names (private, ~name) override
/// them in the node.
struct RosBaseParams {
  std::string cmd_vel_topic = "/cmd_vel";
  std::string odom_topic = "/odom";
  std::string base_frame = "base_link";
  std::string world_frame = "map";  ///< looked up in tf; the odometry's frame when absent
  double odom_timeout_s = 0.5;      ///< older odometry is stale: readState() fails [s]

  /// Throws std::invalid_argument naming the field and value.
  void validate() const;
  template <class V>
  void visit(V& v) {
    v("cmd_vel_topic", cmd_vel_topic, "velocity commands out (geometry_msgs/Twist)");
    v("odom_topic", odom_topic, "odometry in (nav_msgs/Odometry)");
    v("base_frame", base_frame, "the robot frame in tf");
    v("world_frame", world_frame, "the world frame when tf has it");
    v("odom_timeout_s", odom_timeout_s, "older odometry counts as lost [s]");
  }
};

class RosRobotBase : public nav::RobotBase {
 public:
  /// Advertises cmd_vel and subscribes to odom on nh. tf may be nullptr (odometry poses only)
  /// and must outlive the base.
  RosRobotBase(ros::NodeHandle& nh, const RosBaseParams& params, const tf2_ros::Buffer* tf);
  ~RosRobotBase() override;
  RosRobotBase(const RosRobotBase&) = delete;
  RosRobotBase& operator=(const RosRobotBase&) = delete;

  bool readState(nav::BaseState& state) override;
  bool sendVelocity(const nav::Twist2D& command) override;
  bool stop(bool emergency) override;
  /// ROS time (simulated when /use_sim_time is set) [s].
  double timeS() const override;

  /// Why the last readState() failed ("" when it did not).
  std::string lastError() const override;
  /// Whether any odometry arrived.
  bool hasOdometry() const;

 private:
  void onOdom(const nav_msgs::Odometry::ConstPtr& msg);

  RosBaseParams params_;
  const tf2_ros::Buffer* tf_;
  ros::CallbackQueue queue_;
  std::unique_ptr<ros::AsyncSpinner> spinner_;
  ros::Publisher cmd_pub_;
  ros::Subscriber odom_sub_;
  mutable std::mutex mutex_;
  nav_msgs::Odometry::ConstPtr odom_;
  std::string last_error_;
};

/// A RosRobotBase for `upd live --base ros`: initialises ROS as node `upd_live` when no node
/// exists yet (ROS_MASTER_URI names the master) and waits up to wait_s for the first odometry (std::runtime_error naming the topic when none
/// comes).
std::unique_ptr<nav::RobotBase> makeRosBase(const RosBaseParams& params = {}, double wait_s = 5.0);

}  // namespace upd::ros1
