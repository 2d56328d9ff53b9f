// A small ROS 1 bag written with the rosbag API, for the bag tests and the bag fuzzer's seeds:
// depth frames of a wall 1.5 m ahead with their camera info (and, when asked, a point cloud
// half a second after each), the camera on base_link in /tf_static, base_link in map on /tf.
#pragma once

#include "compressed_depth.h"
#include "upd/ros1/conversions.h"

#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include <cstdint>
#include <string>

namespace upd::test {

inline geometry_msgs::TransformStamped stamped(const Eigen::Isometry3d& pose, const std::string& parent,
                                               const std::string& child, double t) {
  return ros1::stampedTransform(pose, parent, child, ros::Time(t));
}

struct SmallBag {
  int width = 64, height = 48;  ///< of the depth image [px]
  int frames = 3;               ///< at t = 1, 2, ... s
  std::uint32_t chunk_bytes = 4000;
  bool with_points = false;  ///< a PointCloud2 on /points after each frame
  rosbag::compression::CompressionType compression = rosbag::compression::Uncompressed;
  /// "png" or "rvl": the depth frames as compressed depth images on the topic image_transport's
  /// compressedDepth plugin publishes; "": raw images.
  std::string depth_codec;
};

/// A camera of w x h px with a 79 degree field of view, centred.
inline core::CameraIntrinsics camera(int w, int h) {
  core::CameraIntrinsics k;
  k.width = w;
  k.height = h;
  k.fx = k.fy = 0.78125 * w;
  k.cx = w / 2.0;
  k.cy = h / 2.0;
  return k;
}

/// The name of a compression, for a test's parameter: None, Bz2, Lz4.
inline std::string compressionName(rosbag::compression::CompressionType c) {
  return c == rosbag::compression::Uncompressed ? "None" : c == rosbag::compression::BZ2 ? "Bz2" : "Lz4";
}

inline void writeSmallBag(const std::string& path, const SmallBag& b) {
  core::DepthImage depth;
  depth.width = b.width;
  depth.height = b.height;
  depth.depth_m.assign(static_cast<std::size_t>(b.width) * b.height, 1.5f);
  const core::CameraIntrinsics k = camera(b.width, b.height);
  core::PointCloud cloud;
  for (int i = 0; i < 8; ++i) cloud.push_back(1.f + 0.1f * i, 0.f, -0.5f);
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(b.compression);
  bag.setChunkThreshold(b.chunk_bytes);
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  tf2_msgs::TFMessage statics;
  statics.transforms.push_back(stamped(identity, "base_link", "camera", 1.0));
  bag.write("/tf_static", ros::Time(1.0), statics);
  sensor_msgs::CameraInfo info = ros1::cameraInfoFromIntrinsics(k);
  sensor_msgs::Image image = ros1::imageFromDepth(depth, "16UC1");
  sensor_msgs::PointCloud2 points = ros1::pointCloud2FromCloud(cloud);
  info.header.frame_id = image.header.frame_id = points.header.frame_id = "camera";
  for (int i = 1; i <= b.frames; ++i) {
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(stamped(identity, "map", "base_link", i));
    bag.write("/tf", ros::Time(i), tf);
    info.header.stamp = image.header.stamp = points.header.stamp = ros::Time(i);
    bag.write("/camera/depth/camera_info", ros::Time(i), info);
    if (b.depth_codec.empty()) {
      bag.write("/camera/depth/image_raw", ros::Time(i), image);
    } else {
      sensor_msgs::CompressedImage packed = compressedDepthOf(depth, "16UC1", b.depth_codec);
      packed.header = image.header;
      bag.write("/camera/depth/image_raw/compressedDepth", ros::Time(i), packed);
    }
    if (b.with_points) bag.write("/points", ros::Time(i + 0.5), points);
  }
}

}  // namespace upd::test
