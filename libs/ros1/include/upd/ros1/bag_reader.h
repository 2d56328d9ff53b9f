// Reading ROS 1 bags (format 2.0; no master, no node): the depth frames (an Image, or a
// compressedDepth CompressedImage, with the latest CameraInfo before it) or PointCloud2 frames of
// a bag in the order of their times, each with the sensor's pose on the robot and the robot's pose
// in the world from the bag's tf (/tf and /tf_static, read in full first, so a transform stamped a
// little after a frame still counts). The bag is read by a reader of the format that checks every
// length and offset first; the messages are deserialized by roscpp.
#pragma once

#include "upd/core/camera.h"
#include "upd/core/point_cloud.h"

#include <Eigen/Geometry>

#include <functional>
#include <map>
#include <optional>
#include <string>

namespace upd::ros1 {

/// Which topics and frames the reader uses.
struct BagTopics {
  std::string depth_topic = "/camera/depth/image_raw";
  std::string camera_info_topic = "/camera/depth/camera_info";
  std::string points_topic = "/points";
  std::string base_frame = "base_link";
  std::string world_frame = "map";   ///< the robot pose: world_frame -> base_frame ...
  std::string odom_frame = "odom";   ///< ... or odom_frame -> base_frame when tf has no map
};

/// One frame of the bag.
struct BagFrame {
  double stamp_s = 0;          ///< the message's header stamp [s]
  std::string sensor_frame;    ///< the message's frame_id
  bool from_depth = false;     ///< a depth image (depth and K set) or a PointCloud2 (cloud set)
  core::DepthImage depth;      ///< [m], camera-optical frame
  core::CameraIntrinsics K;
  core::PointCloud cloud;      ///< PointCloud2 points in sensor_frame
  Eigen::Isometry3d pose_base_sensor = Eigen::Isometry3d::Identity();
  /// The robot in the world at the stamp; empty when tf has neither world frame.
  std::optional<Eigen::Isometry3d> pose_world_base;
};

struct BagReadStats {
  std::size_t messages = 0;  ///< messages on the frame topics
  std::size_t frames = 0;    ///< frames handed to the callback
  std::string world_frame;   ///< the frame the robot poses are in ("" when none)
  std::map<std::string, std::size_t> skipped;  ///< reason -> messages not turned into frames
};

/// Calls on_frame for every frame in time order. A message that does not convert, or whose
/// sensor has no transform to base_frame, is skipped and counted under its reason. Throws
/// std::runtime_error naming the file when the bag cannot be opened or read, and before any
/// frame when it is damaged ("F: damaged bag: <what> (byte N)": the whole bag is walked first)
/// or has no index.
BagReadStats readBag(const std::string& path, const BagTopics& topics,
                     const std::function<void(const BagFrame&)>& on_frame);

/// True for a path ending in ".bag".
bool isBagPath(const std::string& path);

}  // namespace upd::ros1
