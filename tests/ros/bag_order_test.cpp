// A bag's messages are read from its checked chunks in the order rosbag's views give them: by
// their times in the bag, whatever the order they were written in, a batch of chunks at a time.
// The transforms are read in the walk that checks the chunks (one decompression of each chunk
// for the walk and the transforms together), and the chunks it decompressed are kept for the
// read after it, up to a budget. They must be the transforms rosbag's view of /tf
// and /tf_static gives, in its order of time: a bag whose transforms span many
// chunks, a static transform of the camera written twice, in chunks far apart, the later in time
// written first (it replaces the earlier one), and a robot pose written twice at one stamp by
// two publishers, the earlier in time written second (tf2 keeps the first it is given).
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2/buffer_core.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <boost/make_shared.hpp>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "../../libs/ros1/src/bag_walk.h"
#include "small_bag.h"
#include "temp_dir.h"
#include "upd/ros1/bag_reader.h"
#include "upd/ros1/conversions.h"

namespace {

using namespace upd;

Eigen::Isometry3d along(double x, double z = 0.0) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.translation() = Eigen::Vector3d(x, 0.0, z);
  return p;
}

tf2_msgs::TFMessage one(const Eigen::Isometry3d& pose, const std::string& parent,
                        const std::string& child, double stamp) {
  tf2_msgs::TFMessage m;
  m.transforms.push_back(test::stamped(pose, parent, child, stamp));
  return m;
}

// Ten small depth frames at t = 1..10 s in chunks of about 1 kB (then, for a second recording,
// five at t = 0.1..0.5 s), the robot 0.1 m further along x at each; the camera's mount at bag time
// 2 s (z 0.5, written first) and 1 s (z 0.3, written after the 6th frame); at 4 s a second
// publisher's robot pose (x 7) with an earlier bag time than the first's (x 0.3), written after it.
void writeBag(const std::string& path, rosbag::compression::CompressionType compression,
              bool second_recording = false) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.setCompression(compression);
  bag.setChunkThreshold(1000);
  bag.write("/tf_static", ros::Time(2.0), one(along(0.0, 0.5), "base_link", "camera", 2.0));
  core::DepthImage depth;
  depth.width = 16;
  depth.height = 12;
  depth.depth_m.assign(16 * 12, 1.5f);
  sensor_msgs::CameraInfo info = ros1::cameraInfoFromIntrinsics(test::camera(16, 12));
  sensor_msgs::Image image = ros1::imageFromDepth(depth, "16UC1");
  info.header.frame_id = image.header.frame_id = "camera";
  const auto other = boost::make_shared<ros::M_string>(ros::M_string{
      {"callerid", "/other_localizer"},
      {"type", ros::message_traits::datatype<tf2_msgs::TFMessage>()},
      {"md5sum", ros::message_traits::md5sum<tf2_msgs::TFMessage>()},
      {"message_definition", ros::message_traits::definition<tf2_msgs::TFMessage>()}});
  for (int i = 1; i <= 10; ++i) {
    bag.write("/tf", ros::Time(i + 0.02), one(along(0.1 * (i - 1)), "map", "base_link", i));
    if (i == 4)
      bag.write("/tf", ros::Time(i + 0.01), one(along(7.0), "map", "base_link", i), other);
    if (i == 6)
      bag.write("/tf_static", ros::Time(1.0), one(along(0.0, 0.3), "base_link", "camera", 1.0));
    info.header.stamp = image.header.stamp = ros::Time(i);
    bag.write("/camera/depth/camera_info", ros::Time(i + 0.03), info);
    bag.write("/camera/depth/image_raw", ros::Time(i + 0.04), image);
  }
  for (int j = 1; second_recording && j <= 5; ++j) {  // at 0.1 to 0.5 s, after the first
    bag.write("/tf", ros::Time(0.1 * j + 0.002), one(along(-0.1 * j), "map", "base_link", 0.1 * j));
    info.header.stamp = image.header.stamp = ros::Time(0.1 * j);
    bag.write("/camera/depth/camera_info", ros::Time(0.1 * j + 0.003), info);
    bag.write("/camera/depth/image_raw", ros::Time(0.1 * j + 0.004), image);
  }
}

// The transforms as rosbag's view of the transform topics gives them, one after the other.
void loadByView(const std::string& path, tf2::BufferCore& tf) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  for (const rosbag::MessageInstance& m :
       rosbag::View(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf", "/tf_static"}))) {
    const auto msg = m.instantiate<tf2_msgs::TFMessage>();
    for (const auto& t : msg->transforms) tf.setTransform(t, "bag", m.getTopic() == "/tf_static");
  }
}

class BagOrder : public ::testing::TestWithParam<rosbag::compression::CompressionType> {};

TEST_P(BagOrder, TransformsAreRosbagsViewOfThem) {
  test::TempDir dir("bag_tf");
  const std::string path = dir.file("run.bag");
  writeBag(path, GetParam());
  tf2::BufferCore tf(ros::Duration(100.0));
  loadByView(path, tf);
  std::vector<ros1::BagFrame> frames;
  ros1::readBag(path, {}, [&](const ros1::BagFrame& f) { frames.push_back(f); });
  ASSERT_EQ(frames.size(), 10u);
  for (const ros1::BagFrame& f : frames) {
    const ros::Time stamp(f.stamp_s);
    const auto mount =
        ros1::isometryFromTransform(tf.lookupTransform("base_link", "camera", stamp).transform);
    const auto robot =
        ros1::isometryFromTransform(tf.lookupTransform("map", "base_link", stamp).transform);
    EXPECT_TRUE(f.pose_base_sensor.isApprox(mount, 1e-12)) << "frame at " << f.stamp_s;
    ASSERT_TRUE(f.pose_world_base.has_value());
    EXPECT_TRUE(f.pose_world_base->isApprox(robot, 1e-12)) << "frame at " << f.stamp_s;
  }
  EXPECT_DOUBLE_EQ(frames[0].pose_base_sensor.translation().z(), 0.5)
      << "the mount of the later time";
  EXPECT_DOUBLE_EQ(frames[3].pose_world_base->translation().x(), 7.0)
      << "the pose of the earlier time";
  EXPECT_DOUBLE_EQ(frames[4].pose_world_base->translation().x(), 0.4);
}

// A message as read: its topic, time and data.
struct Read {
  std::string topic;
  std::uint64_t time_ns;
  std::vector<std::uint8_t> data;
  bool operator==(const Read& o) const {
    return topic == o.topic && time_ns == o.time_ns && data == o.data;
  }
};

// Every message of the bag as rosbag's view of all its topics gives them.
std::vector<Read> readByView(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::vector<Read> all;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    std::vector<std::uint8_t> data(m.size());
    ros::serialization::OStream stream(data.data(), static_cast<std::uint32_t>(data.size()));
    m.write(stream);
    all.push_back({m.getTopic(), m.getTime().toNSec(), data});
  }
  return all;
}

const std::set<std::string> kAllTopics{"/tf", "/tf_static", "/camera/depth/camera_info",
                                       "/camera/depth/image_raw"};

// Every message on kAllTopics as walk reads them after its check, batch bytes at a time.
std::vector<Read> readAll(ros1::detail::BagWalk& walk, std::uint64_t batch) {
  std::vector<Read> read;
  walk.readMessages(
      kAllTopics,
      [&](const ros1::detail::BagMessage& m) {
        read.push_back({m.topic, m.time_ns, std::vector<std::uint8_t>(m.data, m.data + m.size)});
        return true;
      },
      batch);
  return read;
}

// The bag above, and the frames of a second recording written after it with earlier bag
// times (a bag merged from two: its chunks do not follow each other in time), read a chunk at
// a time, two chunks' bytes at a time and all at once: the messages of rosbag's view.
TEST_P(BagOrder, MessagesComeAsRosbagsView) {
  test::TempDir dir("bag_order");
  const std::string path = dir.file("run.bag");
  writeBag(path, GetParam(), /*second_recording=*/true);
  const std::vector<Read> expected = readByView(path);
  ASSERT_GT(expected.size(), 40u);
  ros1::detail::BagWalk walk(path);
  walk.checkChunks();
  for (const std::uint64_t batch :
       {std::uint64_t{0}, std::uint64_t{2000}, ros1::detail::BagWalk::kBatchBytes}) {
    const std::vector<Read> read = readAll(walk, batch);
    EXPECT_TRUE(read == expected) << "batches of " << batch << " bytes: " << read.size()
                                  << " messages";
  }
  std::vector<double> stamps;
  ros1::readBag(path, {}, [&](const ros1::BagFrame& f) { stamps.push_back(f.stamp_s); });
  EXPECT_TRUE(std::is_sorted(stamps.begin(), stamps.end()));
  EXPECT_EQ(stamps.size(), 15u);
}

// The compressed chunks the check decompressed are kept for the read after it, in the file's
// order up to the budget: with none kept every chunk is decompressed twice, with all kept once,
// with a budget of a few chunks in between; the messages are rosbag's view's in every case.
TEST_P(BagOrder, CheckedChunksAreKeptWithinTheBudget) {
  test::TempDir dir("bag_keep");
  const std::string path = dir.file("run.bag");
  writeBag(path, GetParam(), /*second_recording=*/true);
  const std::vector<Read> expected = readByView(path);
  const bool compressed = GetParam() != rosbag::compression::Uncompressed;
  std::size_t chunks = 0;
  for (const std::uint64_t keep :
       {std::uint64_t{0}, std::uint64_t{4000}, ros1::detail::BagWalk::defaultKeepBytes()}) {
    ros1::detail::BagWalk walk(path, keep);
    walk.checkChunks();
    if (keep == 0) chunks = walk.decompressions();
    EXPECT_EQ(walk.decompressions(), chunks) << "the check decompresses every chunk once";
    for (const std::uint64_t batch : {std::uint64_t{0}, ros1::detail::BagWalk::kBatchBytes}) {
      const std::size_t before = walk.decompressions();
      EXPECT_TRUE(readAll(walk, batch) == expected) << "keep " << keep << ", batch " << batch;
      const std::size_t again = walk.decompressions() - before;
      if (keep == 0) {
        // (A chunk at a time, a chunk of the merged bag is met twice.)
        EXPECT_GE(again, chunks) << "nothing kept: every chunk decompressed again";
      } else if (keep == 4000 && compressed) {
        EXPECT_GT(again, 0u) << "a few chunks kept, the rest decompressed again";
        EXPECT_LT(again, chunks) << "a few chunks kept";
      } else {
        EXPECT_EQ(again, 0u) << "every chunk kept";
      }
    }
  }
  if (compressed) {
    EXPECT_GT(chunks, 10u);
  } else {
    EXPECT_EQ(chunks, 0u) << "uncompressed chunks are read in place";
  }
}

INSTANTIATE_TEST_SUITE_P(Compressions, BagOrder,
                         ::testing::Values(rosbag::compression::Uncompressed,
                                           rosbag::compression::BZ2, rosbag::compression::LZ4),
                         [](const auto& p) { return test::compressionName(p.param); });

}  // namespace
