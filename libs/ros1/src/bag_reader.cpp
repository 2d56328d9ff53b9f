#include "upd/ros1/bag_reader.h"

#include "upd/ros1/conversions.h"

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

namespace upd::ros1 {

namespace {

// Every transform of the bag in a buffer that keeps them all.
void loadTf(rosbag::Bag& bag, tf2::BufferCore& tf) {
  rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}));
  for (const rosbag::MessageInstance& m : view) {
    const auto msg = m.instantiate<tf2_msgs::TFMessage>();
    if (!msg) continue;
    const bool is_static = m.getTopic() == "/tf_static";
    for (const auto& t : msg->transforms) tf.setTransform(t, "bag", is_static);
  }
}

std::optional<Eigen::Isometry3d> lookup(const tf2::BufferCore& tf, const std::string& target,
                                        const std::string& source, const ros::Time& stamp) {
  try {
    return isometryFromTransform(tf.lookupTransform(target, source, stamp).transform);
  } catch (const tf2::TransformException&) {
    return std::nullopt;
  }
}

// The pose parts of a frame from tf: false (and the reason counted) when the sensor has none.
bool framePoses(const tf2::BufferCore& tf, const BagTopics& topics, const ros::Time& stamp,
                BagFrame& frame, BagReadStats& stats) {
  const auto base_sensor = lookup(tf, topics.base_frame, frame.sensor_frame, stamp);
  if (!base_sensor) {
    ++stats.skipped["no tf " + topics.base_frame + " -> " + frame.sensor_frame];
    return false;
  }
  frame.pose_base_sensor = *base_sensor;
  frame.pose_world_base.reset();
  for (const std::string& w : {topics.world_frame, topics.odom_frame}) {
    if (!stats.world_frame.empty() && w != stats.world_frame) continue;
    if (auto p = lookup(tf, w, topics.base_frame, stamp)) {
      frame.pose_world_base = p;
      stats.world_frame = w;
      break;
    }
  }
  return true;
}

}  // namespace

bool isBagPath(const std::string& path) {
  return path.size() > 4 && path.compare(path.size() - 4, 4, ".bag") == 0;
}

BagReadStats readBag(const std::string& path, const BagTopics& topics,
                     const std::function<void(const BagFrame&)>& on_frame) {
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error(path + ": cannot open as a ROS 1 bag: " + e.what());
  }
  BagReadStats stats;
  try {
    rosbag::View all(bag);
    const double span_s = (all.getEndTime() - all.getBeginTime()).toSec();
    tf2::BufferCore tf(ros::Duration(span_s + 60.0));
    loadTf(bag, tf);
    // The first CameraInfo serves the images before it: a bag orders messages of the same
    // stamp by connection, so an image may come just before its info.
    sensor_msgs::CameraInfo::ConstPtr info;
    for (const rosbag::MessageInstance& m :
         rosbag::View(bag, rosbag::TopicQuery(topics.camera_info_topic))) {
      if ((info = m.instantiate<sensor_msgs::CameraInfo>())) break;
    }
    rosbag::View view(bag, rosbag::TopicQuery(std::vector<std::string>{
                               topics.depth_topic, topics.camera_info_topic, topics.points_topic}));
    BagFrame frame;
    for (const rosbag::MessageInstance& m : view) {
      if (auto i = m.instantiate<sensor_msgs::CameraInfo>()) {
        info = i;
        continue;
      }
      ++stats.messages;
      const auto image = m.instantiate<sensor_msgs::Image>();
      const auto points = image ? nullptr : m.instantiate<sensor_msgs::PointCloud2>();
      if (!image && !points) {
        ++stats.skipped["unexpected type " + m.getDataType() + " on " + m.getTopic()];
        continue;
      }
      const std_msgs::Header& header = image ? image->header : points->header;
      frame.stamp_s = header.stamp.toSec();
      frame.sensor_frame = header.frame_id;
      frame.from_depth = image != nullptr;
      try {
        if (image) {
          if (!info) throw MessageError("depth image before any CameraInfo");
          frame.K = intrinsicsFromCameraInfo(*info);
          frame.depth = depthFromImage(*image);
          if (frame.depth.width != frame.K.width || frame.depth.height != frame.K.height)
            throw MessageError("depth image and CameraInfo sizes differ");
        } else {
          frame.cloud = cloudFromPointCloud2(*points);
        }
      } catch (const MessageError& e) {
        ++stats.skipped[e.what()];
        continue;
      }
      if (!framePoses(tf, topics, header.stamp, frame, stats)) continue;
      on_frame(frame);
      ++stats.frames;
    }
  } catch (const rosbag::BagException& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
  return stats;
}

}  // namespace upd::ros1
