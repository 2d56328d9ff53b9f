// ROS 1 bags: a bag written with the rosbag API from a real depth frame (Image + CameraInfo,
// the camera on base_link in /tf_static, the robot moving in /tf) reads back frame by frame with
// its poses, and `upd playback RUN.bag` turns it into a map as it does a rawlog.
#include "compressed_depth.h"
#include "real_frame.h"
#include "small_bag.h"
#include "temp_dir.h"
#include "test_data.h"
#include "apps/run_upd.h"

#include "upd/ros1/bag_reader.h"
#include "upd/ros1/conversions.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <rosbag/bag.h>
#include <tf2_msgs/TFMessage.h>

#include <fstream>
#include <iostream>

namespace {

using namespace upd;

using test::stamped;

// Three copies of the frame at t = 1, 2, 3 s with the robot 0.1 m further along x each time,
// and one malformed image between them; with a codec ("png", "rvl"), as compressed depth images
// on the topic image_transport's compressedDepth plugin publishes.
void writeBag(const std::string& path, const test::RealFrame& f, const std::string& codec = "") {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  tf2_msgs::TFMessage statics;
  statics.transforms.push_back(stamped(f.pose_base_optical, "base_link", "camera_optical", 1.0));
  bag.write("/tf_static", ros::Time(1.0), statics);
  sensor_msgs::CameraInfo info = ros1::cameraInfoFromIntrinsics(f.K);
  sensor_msgs::Image image = ros1::imageFromDepth(f.depth, "16UC1");
  info.header.frame_id = image.header.frame_id = "camera_optical";
  for (int i = 1; i <= 3; ++i) {
    const double t = i;
    Eigen::Isometry3d robot = Eigen::Isometry3d::Identity();
    robot.translation().x() = 0.1 * (i - 1);
    tf2_msgs::TFMessage tf;
    tf.transforms.push_back(stamped(robot, "map", "base_link", t));
    bag.write("/tf", ros::Time(t), tf);
    info.header.stamp = image.header.stamp = ros::Time(t);
    bag.write("/camera/depth/camera_info", ros::Time(t), info);
    if (!codec.empty()) {
      sensor_msgs::CompressedImage packed = test::compressedDepthOf(f.depth, "16UC1", codec);
      packed.header = image.header;
      bag.write("/camera/depth/image_raw/compressedDepth", ros::Time(t), packed);
      if (i == 2) {
        packed.format = "rgb8; compressedDepth " + codec;
        bag.write("/camera/depth/image_raw/compressedDepth", ros::Time(t + 0.5), packed);
      }
      continue;
    }
    bag.write("/camera/depth/image_raw", ros::Time(t), image);
    if (i == 2) {
      sensor_msgs::Image bad = image;
      bad.encoding = "rgb8";
      bag.write("/camera/depth/image_raw", ros::Time(t + 0.5), bad);
    }
  }
  bag.close();
}

class RosBag : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string png = test::sharedFile("rtabmap/rgbd/depth/17.png");
    const std::string yaml = test::sharedFile("rtabmap/rgbd/calib/17.yaml");
    if (png.empty() || yaml.empty()) GTEST_SKIP() << "rtabmap/rgbd frame 17 not in the shared data";
    frame = test::loadRealFrame(png, yaml);
    bag_path = (dir.path() / "run.bag").string();
    writeBag(bag_path, frame);
  }
  test::TempDir dir;
  test::RealFrame frame;
  std::string bag_path;
};

TEST_F(RosBag, ReadsEveryGoodFrameWithItsPosesAndCountsTheBadOne) {
  std::vector<ros1::BagFrame> frames;
  const ros1::BagReadStats stats =
      ros1::readBag(bag_path, {}, [&](const ros1::BagFrame& f) { frames.push_back(f); });
  for (const auto& [reason, n] : stats.skipped) std::cerr << n << " skipped: " << reason << "\n";
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(stats.messages, 4u);
  ASSERT_EQ(stats.skipped.size(), 1u);
  EXPECT_NE(stats.skipped.begin()->first.find("encoding 'rgb8'"), std::string::npos);
  EXPECT_EQ(stats.world_frame, "map");
  for (int i = 0; i < 3; ++i) {
    const ros1::BagFrame& f = frames[i];
    EXPECT_TRUE(f.from_depth);
    EXPECT_DOUBLE_EQ(f.stamp_s, i + 1.0);
    EXPECT_EQ(f.depth.width, frame.K.width);
    EXPECT_TRUE(f.pose_base_sensor.isApprox(frame.pose_base_optical, 1e-9));
    ASSERT_TRUE(f.pose_world_base.has_value());
    EXPECT_NEAR(f.pose_world_base->translation().x(), 0.1 * i, 1e-9);
  }
}

// A bag of compressed depth images (image_transport's compressedDepth: what a robot records to
// save space) reads back as the same frames as the raw images, PNG or RVL, and plays back into
// the same map.
TEST_F(RosBag, CompressedDepthImagesReadAsTheRawOnes) {
  std::vector<ros1::BagFrame> raw;
  ros1::readBag(bag_path, {}, [&](const ros1::BagFrame& f) { raw.push_back(f); });
  ASSERT_EQ(raw.size(), 3u);
  for (const std::string codec : {"png", "rvl"}) {
    const std::string packed_path = (dir.path() / ("packed-" + codec + ".bag")).string();
    writeBag(packed_path, frame, codec);
    std::vector<ros1::BagFrame> frames;
    const ros1::BagReadStats stats =
        ros1::readBag(packed_path, {}, [&](const ros1::BagFrame& f) { frames.push_back(f); });
    ASSERT_EQ(frames.size(), 3u) << codec;
    EXPECT_EQ(stats.messages, 4u);
    ASSERT_EQ(stats.skipped.size(), 1u);
    EXPECT_NE(stats.skipped.begin()->first.find("format 'rgb8; compressedDepth"),
              std::string::npos) << stats.skipped.begin()->first;
    for (int i = 0; i < 3; ++i) {
      EXPECT_DOUBLE_EQ(frames[i].stamp_s, raw[i].stamp_s);
      EXPECT_EQ(frames[i].depth.depth_m, raw[i].depth.depth_m) << codec << " frame " << i;
      ASSERT_TRUE(frames[i].pose_world_base.has_value());
      EXPECT_TRUE(frames[i].pose_world_base->isApprox(*raw[i].pose_world_base, 1e-12));
    }
  }
  const auto out = [&](const std::string& name) { return (dir.path() / name).string(); };
  const std::string config = std::string(" --config ") + UPD_SOURCE_DIR + "/config/dune-kinect.ini";
  const auto a = test::runUpd("playback " + bag_path + config + " --output " + out("a") + " --quiet");
  const auto b = test::runUpd("playback " + out("packed-rvl.bag") + config + " --output " +
                              out("b") + " --quiet");
  ASSERT_EQ(a.exit_code, 0) << a.output;
  ASSERT_EQ(b.exit_code, 0) << b.output;
  std::ifstream ja(dir.path() / "a" / "summary.json"), jb(dir.path() / "b" / "summary.json");
  const nlohmann::json sa = nlohmann::json::parse(ja), sb = nlohmann::json::parse(jb);
  EXPECT_EQ(sb["frames_processed"], 3);
  EXPECT_EQ(sa["grid"], sb["grid"]);
}

TEST_F(RosBag, PlaysBackIntoAMapLikeARawlog) {
  const auto out = dir.path() / "out";
  const auto r = test::runUpd("playback " + bag_path + " --config " + UPD_SOURCE_DIR +
                              "/config/dune-kinect.ini --output " + out.string() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 frames"), std::string::npos) << r.output;
  std::ifstream in(out / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in);
  EXPECT_EQ(s["frames_processed"], 3);
  EXPECT_EQ(s["pose_source"], "ground truth") << s.dump(2);
  EXPECT_GT(s["grid"]["traversable"].get<int>(), 100) << "the floor of the room is mapped";
  EXPECT_TRUE(std::filesystem::exists(out / "bag.rawlog"));
  std::ifstream tum(out / "bag_poses.tum");
  int lines = 0;
  for (std::string l; std::getline(tum, l);) ++lines;
  EXPECT_EQ(lines, 3);
  EXPECT_TRUE(std::filesystem::exists(out / "map.png"));

  // A bag without frames on the expected topics: one line, status 1, no map.
  const std::string empty = (dir.path() / "empty.bag").string();
  {
    rosbag::Bag bag(empty, rosbag::bagmode::Write);
    tf2_msgs::TFMessage tf;
    bag.write("/tf", ros::Time(1.0), tf);
  }
  const auto bad = test::runUpd("playback " + empty + " --config " + UPD_SOURCE_DIR +
                                "/config/dune-kinect.ini --output " + (dir.path() / "o2").string());
  EXPECT_EQ(bad.exit_code, 1) << bad.output;
  EXPECT_NE(bad.output.find("no depth or PointCloud2 frame"), std::string::npos) << bad.output;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "o2" / "map.png"));
}

}  // namespace
