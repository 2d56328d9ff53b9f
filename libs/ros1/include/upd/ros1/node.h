// The `upd ros` node: depth frames (or point clouds) in, the traversability map, the scored
// cloud and the route out, and, given a goal, the robot driven there through RosRobotBase.
//
// Inputs: sensor_msgs/Image depth + sensor_msgs/CameraInfo, or sensor_msgs/PointCloud2; the
// sensor pose from tf (world_frame -> the message's frame, through base_frame), the world frame
// being `map` when tf has map -> base_link at the first frame and `odom` otherwise. Every frame
// is scored and fused by the navigation loop (upd/nav/navigation_loop.h).
// Outputs: nav_msgs/OccupancyGrid (latched), the scored points as PointCloud2 (x y z zeta label
// cost), the route as visualization_msgs/MarkerArray; on a goal (geometry_msgs/PoseStamped) the
// loop plans and MRPT's reactive navigator sends geometry_msgs/Twist commands.
// Failures stop the robot (a zero command) with one log line: the goal reached or given up,
// sensor data older than sensor_timeout_s while driving, a transform tf does not have, a
// message that does not convert (conversions.h), odometry that stops.
#pragma once

#include "upd/nav/nav_config.h"
#include "upd/ros1/ros_base.h"

#include <ros/ros.h>

#include <memory>
#include <string>

namespace upd::ros1 {

/// Topics, frames and timing of the node; each is a private ROS parameter of the same name
/// (`~depth_topic`, ...) with these defaults.
struct RosNodeParams {
  std::string depth_topic = "/camera/depth/image_raw";
  /// "raw": sensor_msgs/Image on depth_topic; "compressedDepth": sensor_msgs/CompressedImage on
  /// depth_topic/compressedDepth (image_transport's compressed depth plugin), as image_transport
  /// subscribers choose by their `~image_transport` parameter.
  std::string image_transport = "raw";
  std::string camera_info_topic = "/camera/depth/camera_info";
  std::string points_topic = "/points";
  std::string goal_topic = "/move_base_simple/goal";
  std::string grid_topic = "/upd/traversability";
  std::string cloud_topic = "/upd/cloud";
  std::string route_topic = "/upd/route";
  std::string odom_frame = "odom";  ///< the world frame when tf has no world_frame
  RosBaseParams base;               ///< cmd_vel, odom, base_frame, world_frame (map)
  double sensor_timeout_s = 1.0;    ///< no frame for longer while driving: stop [s]
  double tf_timeout_s = 0.2;        ///< wait this long for a frame's transform [s]
  double control_rate_hz = 10.0;    ///< navigator steps per second [Hz]
  double grid_period_s = 0.5;       ///< the grid is published at most this often [s]

  /// Throws std::invalid_argument naming the field and value.
  void validate() const;
  /// The topic the depth arrives on: depth_topic, or depth_topic/compressedDepth.
  std::string depthImageTopic() const;
  template <class V>
  void visit(V& v) {
    v("depth_topic", depth_topic, "depth image in (sensor_msgs/Image, 16UC1 mm or 32FC1 m)");
    v("image_transport", image_transport,
      "raw, or compressedDepth: its CompressedImage on depth_topic/compressedDepth");
    v("camera_info_topic", camera_info_topic, "its camera info in");
    v("points_topic", points_topic, "point cloud in (sensor_msgs/PointCloud2)");
    v("goal_topic", goal_topic, "goals in (geometry_msgs/PoseStamped)");
    v("grid_topic", grid_topic, "the traversability grid out (nav_msgs/OccupancyGrid, latched)");
    v("cloud_topic", cloud_topic, "the scored cloud out (x y z zeta label cost)");
    v("route_topic", route_topic, "the route out (visualization_msgs/MarkerArray)");
    v("odom_frame", odom_frame, "the world frame when tf has no world_frame");
    base.visit(v);
    v("sensor_timeout_s", sensor_timeout_s, "while driving, no frame for longer stops the robot [s]");
    v("tf_timeout_s", tf_timeout_s, "how long a frame waits for its transform [s]");
    v("control_rate_hz", control_rate_hz, "navigator steps per second [Hz]");
    v("grid_period_s", grid_period_s, "the grid is published at most this often [s]");
  }
};

/// defaults overridden by the private parameters of private_nh that are set.
RosNodeParams loadRosNodeParams(const ros::NodeHandle& private_nh, RosNodeParams defaults = {});

/// How a run of the node ended.
enum class NodeEnd { Shutdown, GoalReached, GoalFailed };

class TraversabilityNode {
 public:
  /// Subscribes and advertises on nh; builds the loop from config (the navigator itself on the
  /// first goal).
  TraversabilityNode(ros::NodeHandle& nh, const RosNodeParams& params, const nav::NavConfig& config);
  ~TraversabilityNode();
  TraversabilityNode(const TraversabilityNode&) = delete;
  TraversabilityNode& operator=(const TraversabilityNode&) = delete;

  /// Runs the control loop until ROS shuts down, or, with exit_after_goal, until the first
  /// goal ends (reached or failed).
  NodeEnd spin(bool exit_after_goal);
  int framesProcessed() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace upd::ros1
