#include "upd/ros1/bag_reader.h"

#include "upd/ros1/conversions.h"

#include "bag_walk.h"
#include "bag_messages.h"

#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include <boost/make_shared.hpp>

#include <algorithm>
#include <cstdint>
#include <functional>
#include <new>
#include <optional>
#include <string>
#include <set>
#include <utility>
#include <vector>

namespace upd::ros1 {

namespace {

// Counts a message on topic that does not deserialize, and why.
void countUndeserialized(BagReadStats& stats, const std::string& topic, const std::string& why) {
  ++stats.skipped["a message on " + topic + " that does not deserialize (" + why + ")"];
}

// Message M from its serialized data: null where its data does not deserialize, counted under
// its reason: a string or array length that runs past its data (checked first, by M's layout
// whatever type the bag names: roscpp would allocate what a length says), or what roscpp throws.
template <class M>
boost::shared_ptr<M> decoded(const std::string& topic, const std::uint8_t* data, std::size_t size,
                             BagReadStats& stats) {
  if (!detail::lengthsFit(ros::message_traits::datatype<M>(), data, size)) {
    countUndeserialized(stats, topic, "a length runs past its data");
    return nullptr;
  }
  try {
    auto msg = boost::make_shared<M>();
    ros::serialization::IStream in(const_cast<std::uint8_t*>(data), static_cast<std::uint32_t>(size));
    ros::serialization::deserialize(in, *msg);
    return msg;
  } catch (const ros::Exception& e) {
    countUndeserialized(stats, topic, e.what());
  } catch (const std::bad_alloc&) {
    countUndeserialized(stats, topic, "a length beyond memory");
  }
  return nullptr;
}

// Whether a connection's messages are of type M, as rosbag's MessageInstance::isType asks.
template <class M>
bool isType(const std::string& md5sum) {
  const std::string m = ros::message_traits::MD5Sum<M>::value();
  return m == "*" || m == md5sum;
}

// The message as type M: null when it is another type, or (counted) where it does not
// deserialize.
template <class M>
boost::shared_ptr<M> instantiate(const detail::BagMessage& m, BagReadStats& stats) {
  return isType<M>(m.md5sum) ? decoded<M>(m.topic, m.data, m.size, stats) : nullptr;
}

// The bag's transforms, from the walk of its chunks (which decompresses them once): /tf as
// met, /tf_static kept until the walk ends and then set in the order of their times, for a
// later static transform of a frame replaces an earlier one.
class TfFromWalk {
 public:
  TfFromWalk(tf2::BufferCore& tf, BagReadStats& stats) : tf_(tf), stats_(stats) {}
  static std::set<std::string> topics() { return {"/tf", "/tf_static"}; }
  void operator()(const detail::BagMessage& m) {
    const auto msg = instantiate<tf2_msgs::TFMessage>(m, stats_);
    if (!msg) return;
    if (m.topic == "/tf_static") {
      statics_.emplace_back(m.time_ns, msg);
      return;
    }
    for (const auto& t : msg->transforms) tf_.setTransform(t, "bag", false);
  }
  void setStatics() {
    std::stable_sort(statics_.begin(), statics_.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (const auto& [time, msg] : statics_) {
      for (const auto& t : msg->transforms) tf_.setTransform(t, "bag", true);
    }
  }

 private:
  tf2::BufferCore& tf_;
  BagReadStats& stats_;
  std::vector<std::pair<std::uint64_t, tf2_msgs::TFMessage::ConstPtr>> statics_;
};

std::optional<Eigen::Isometry3d> lookup(const tf2::BufferCore& tf, const std::string& target,
                                        const std::string& source, const ros::Time& stamp) {
  try {
    return isometryFromTransform(tf.lookupTransform(target, source, stamp).transform);
  } catch (const std::runtime_error&) {
    // tf2::TransformException, and ros::Duration's range error where a damaged stamp lies
    // more than 2^31 s from the transforms (tf2 throws it while it words its extrapolation)
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

// The depth images' topic: the one named, or the compressedDepth topic image_transport publishes
// beside it (`<topic>/compressedDepth`) where the bag has no message on the one named.
std::string depthTopicOf(const detail::BagWalk& bag, const std::string& depth_topic) {
  const std::string compressed = compressedDepthTopic(depth_topic);
  return !bag.hasMessages(depth_topic) && bag.hasMessages(compressed) ? compressed : depth_topic;
}

// The frame of message m (a depth image, raw or compressed, with the CameraInfo info; or a
// PointCloud2) into frame and header, without its poses: false (and the reason counted) where
// the message is of another type, does not deserialize, or does not convert.
bool frameOf(const detail::BagMessage& m, const sensor_msgs::CameraInfo* info, BagFrame& frame,
             std_msgs::Header& header, BagReadStats& stats) {
  sensor_msgs::Image::ConstPtr image;
  sensor_msgs::CompressedImage::ConstPtr packed;
  sensor_msgs::PointCloud2::ConstPtr points;
  if (isType<sensor_msgs::Image>(m.md5sum)) {
    image = instantiate<sensor_msgs::Image>(m, stats);
  } else if (isType<sensor_msgs::CompressedImage>(m.md5sum)) {
    packed = instantiate<sensor_msgs::CompressedImage>(m, stats);
  } else if (isType<sensor_msgs::PointCloud2>(m.md5sum)) {
    points = instantiate<sensor_msgs::PointCloud2>(m, stats);
  } else {
    ++stats.skipped["unexpected type " + m.datatype + " on " + m.topic];
    return false;
  }
  if (!image && !packed && !points) return false;  // counted: its data does not deserialize
  header = image ? image->header : packed ? packed->header : points->header;
  frame.stamp_s = header.stamp.toSec();
  frame.sensor_frame = header.frame_id;
  frame.from_depth = !points;
  try {
    if (points) {
      frame.cloud = cloudFromPointCloud2(*points);
      return true;
    }
    if (!info) throw MessageError("depth image before any CameraInfo");
    frame.depth = image ? depthFromImage(*image) : depthFromCompressedDepth(*packed);
    frame.K = intrinsicsForDepth(frame.depth, *info);
  } catch (const MessageError& e) {
    ++stats.skipped[e.what()];
    return false;
  }
  return true;
}

}  // namespace

bool isBagPath(const std::string& path) {
  return path.size() > 4 && path.compare(path.size() - 4, 4, ".bag") == 0;
}

BagReadStats readBag(const std::string& path, const BagTopics& topics,
                     const std::function<void(const BagFrame&)>& on_frame) {
  BagReadStats stats;
  try {
    detail::BagWalk bag(path);
    // In seconds: a span beyond ros::Duration's 2^31 s (a damaged stamp) would throw.
    const double span_s = bag.beginNs() > bag.endNs() ? 0.0 : (bag.endNs() - bag.beginNs()) * 1e-9;
    tf2::BufferCore tf(ros::Duration(std::clamp(span_s + 60.0, 60.0, 2e9)));
    TfFromWalk transforms(tf, stats);
    bag.checkChunks(TfFromWalk::topics(), std::ref(transforms));
    transforms.setStatics();
    // The first CameraInfo serves the images before it (an image received, and recorded, just
    // before its info).
    sensor_msgs::CameraInfo::ConstPtr info;
    bag.readMessages(
        {topics.camera_info_topic},
        [&](const detail::BagMessage& m) {
          BagReadStats counted_below;  // the loop below meets this message again
          info = instantiate<sensor_msgs::CameraInfo>(m, counted_below);
          return !info;
        },
        0);
    BagFrame frame;
    bag.readMessages(
        {depthTopicOf(bag, topics.depth_topic), topics.camera_info_topic, topics.points_topic},
        [&](const detail::BagMessage& m) {
          if (isType<sensor_msgs::CameraInfo>(m.md5sum)) {
            if (auto i = instantiate<sensor_msgs::CameraInfo>(m, stats)) info = i;
            return true;
          }
          ++stats.messages;
          std_msgs::Header header;
          if (!frameOf(m, info.get(), frame, header, stats)) return true;
          if (!framePoses(tf, topics, header.stamp, frame, stats)) return true;
          on_frame(frame);
          ++stats.frames;
          return true;
        });
  } catch (const detail::NotABag& e) {
    throw std::runtime_error(path + ": cannot open as a ROS 1 bag: " + e.what());
  } catch (const detail::BagDamage& e) {
    throw std::runtime_error(path + ": damaged bag: " + e.what());
  }
  return stats;
}

}  // namespace upd::ros1
