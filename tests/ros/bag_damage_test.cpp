// Damaged ROS 1 bags: rosbag_storage trusts the lengths and offsets it reads, so a bag is walked
// before rosbag reads it. A bag written here with the rosbag API (uncompressed, BZ2 and LZ4
// chunks: three depth frames with their camera info and transforms) is cut short, left without
// its index, and has bytes flipped at random; every read ends in its frames or in one
// std::runtime_error that names the file, and never ends the process.
#include "small_bag.h"
#include "sanitizer.h"
#include "temp_dir.h"

#include "upd/ros1/bag_reader.h"
#include "upd/ros1/conversions.h"

#include "../../libs/ros1/src/bag_messages.h"

#include <boost/make_shared.hpp>
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace upd;

using test::stamped;

// Three small depth frames (a wall 1.5 m ahead) in chunks of about 4 kB; the file's bytes.
std::string writeBag(const std::string& path, rosbag::compression::CompressionType compression) {
  test::SmallBag b;
  b.compression = compression;
  test::writeSmallBag(path, b);
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The frames read, or -1 with the error in `error`; any other exception fails the test.
int framesOf(const std::string& path, std::string& error) {
  int frames = 0;
  try {
    ros1::readBag(path, {}, [&](const ros1::BagFrame&) { ++frames; });
  } catch (const std::runtime_error& e) {
    error = e.what();
    return -1;
  }
  return frames;
}

void write(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

class BagDamage : public ::testing::TestWithParam<rosbag::compression::CompressionType> {
 protected:
  test::TempDir dir{"bag_damage"};
  std::string good = dir.file("good.bag");
  std::string bytes = writeBag(good, GetParam());
  std::string bad = dir.file("bad.bag");
};

TEST_P(BagDamage, SoundBagReadsEveryFrame) {
  std::string error;
  EXPECT_EQ(framesOf(good, error), 3) << error;
}

TEST_P(BagDamage, CutShortIsOneErrorNamingTheFile) {
  for (std::size_t cut = 0; cut < bytes.size(); cut += 13) {
    write(bad, bytes.substr(0, cut));
    std::string error;
    ASSERT_EQ(framesOf(bad, error), -1) << "cut at " << cut;
    ASSERT_EQ(error.rfind(bad + ": ", 0), 0u) << error;
    ASSERT_EQ(error.find('\n'), std::string::npos) << error;
  }
  // Inside its first chunk (its file header is padded to 4 kB), the cut is named as such.
  write(bad, bytes.substr(0, 4200));
  std::string error;
  framesOf(bad, error);
  EXPECT_NE(error.find("damaged bag: the file ends at byte 4200, before its index"),
            std::string::npos)
      << error;
}

// A recording that did not end: rosbag leaves the index position of the file header at 0.
TEST_P(BagDamage, BagWithoutIndexSaysHowToRepairIt) {
  std::string unindexed = bytes;
  const auto at = unindexed.find("index_pos=");
  ASSERT_NE(at, std::string::npos);
  unindexed.replace(at + 10, 8, std::string(8, '\0'));
  write(bad, unindexed);
  std::string error;
  ASSERT_EQ(framesOf(bad, error), -1);
  EXPECT_NE(error.find(bad + ": damaged bag: the bag has no index"), std::string::npos) << error;
  EXPECT_NE(error.find("rosbag reindex"), std::string::npos) << error;
}

// Three bytes flipped at random positions, 400 times (a fixed seed). Before the walk, rosbag
// read past a chunk's data and ended the process (SIGSEGV) within the first few hundred.
TEST_P(BagDamage, FlippedBytesEndInFramesOrOneErrorNamingTheFile) {
  std::mt19937 rng(1);
  int failed = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::string flipped = bytes;
    for (int f = 0; f < 3; ++f) flipped[rng() % flipped.size()] = static_cast<char>(rng());
    write(bad, flipped);
    std::string error;
    const int frames = framesOf(bad, error);
    if (frames >= 0) {
      ASSERT_LE(frames, 3);
      continue;
    }
    ++failed;
    ASSERT_EQ(error.rfind(bad + ": ", 0), 0u) << "trial " << trial << ": " << error;
  }
  EXPECT_GT(failed, 0);
}

// rosbag reads the first line with fgets and sscanf("#ROS%s V%d.%d") into a 100-byte word: a
// line that goes on after "#ROSBAG V2.0" is still a bag of format 2.0 to it (its file header then
// starts later: garbage lengths), a longer word overflows its buffer, and 1.2 is another reader.
// Its version is major * 100 + minor, so "V1.100" is 2.0 too; a major of 13 digits is not (the
// reader's own arithmetic overflowed on it, found by fuzz_bag), and is named as written.
TEST(BagVersionLine, IsReadAsRosbagReadsIt) {
  const test::TempDir dir("bag_version");
  const std::string bytes = writeBag(dir.file("good.bag"), rosbag::compression::Uncompressed);
  const std::string bad = dir.file("bad.bag");
  struct Case {
    std::string bytes, expected;
  };
  const std::string rest = bytes.substr(13);
  for (const Case& c :
       {Case{"#ROSBAG V2.0 " + rest, "damaged bag: "},
        Case{"#ROS" + std::string(150, 'A') + " V2.0\n" + rest, "word after '#ROS' has 100 or more"},
        Case{"#ROSBAG V1.2\n" + rest, "damaged bag: bag format 1.2: only format 2.0"},
        Case{"#ROSBAG V4444444444442.4444\n" + rest,
             "damaged bag: bag format 4444444444442.4444: only format 2.0"},
        Case{"#ROSBAG V-2147483648.0\n" + rest, "damaged bag: bag format -2147483648.0: only"},
        Case{"#ROSBAG V1.100\n" + rest, "damaged bag: "}}) {
    write(bad, c.bytes);
    std::string error;
    ASSERT_EQ(framesOf(bad, error), -1) << c.expected;
    EXPECT_EQ(error.rfind(bad + ": ", 0), 0u) << error;
    EXPECT_NE(error.find(c.expected), std::string::npos) << error;
    if (c.bytes.rfind("#ROSBAG V1.100", 0) == 0) {
      EXPECT_EQ(error.find("bag format"), std::string::npos) << "read as format 2.0: " << error;
    }
  }
  write(bad, "not a bag\n");
  std::string error;
  ASSERT_EQ(framesOf(bad, error), -1);
  EXPECT_NE(error.find(bad + ": cannot open as a ROS 1 bag"), std::string::npos) << error;
}

// The serialized data of a message.
template <class M>
std::vector<std::uint8_t> serialized(const M& msg) {
  std::vector<std::uint8_t> raw(ros::serialization::serializationLength(msg));
  ros::serialization::OStream stream(raw.data(), static_cast<std::uint32_t>(raw.size()));
  ros::serialization::serialize(stream, msg);
  return raw;
}

// Every message type the reader instantiates: whole, its lengths fit; cut anywhere, or with a
// length raised past its data, they do not (roscpp would allocate what the length says).
TEST(BagMessages, LengthsThatRunPastTheDataAreFound) {
  core::DepthImage depth;
  depth.width = 4;
  depth.height = 3;
  depth.depth_m.assign(12, 1.f);
  core::CameraIntrinsics k;
  k.width = 4;
  k.height = 3;
  k.fx = k.fy = 5;
  core::PointCloud cloud;
  cloud.push_back(1.f, 2.f, 3.f);
  tf2_msgs::TFMessage tf;
  const Eigen::Isometry3d identity = Eigen::Isometry3d::Identity();
  tf.transforms.push_back(stamped(identity, "map", "base_link", 1.0));
  tf.transforms.push_back(stamped(identity, "base_link", "camera", 1.0));
  const std::vector<std::pair<std::string, std::vector<std::uint8_t>>> messages = {
      {"sensor_msgs/Image", serialized(ros1::imageFromDepth(depth, "16UC1"))},
      {"sensor_msgs/CameraInfo", serialized(ros1::cameraInfoFromIntrinsics(k))},
      {"sensor_msgs/PointCloud2", serialized(ros1::pointCloud2FromCloud(cloud))},
      {"tf2_msgs/TFMessage", serialized(tf)},
      {"sensor_msgs/CompressedImage", serialized(test::compressedDepthOf(depth, "16UC1", "rvl"))}};
  for (const auto& [type, raw] : messages) {
    EXPECT_TRUE(ros1::detail::lengthsFit(type, raw.data(), raw.size())) << type;
    for (std::size_t cut = 0; cut < raw.size(); ++cut) {
      EXPECT_FALSE(ros1::detail::lengthsFit(type, raw.data(), cut)) << type << " cut at " << cut;
    }
  }
  // The image's data length (its last 4 bytes before the 24 bytes of data) raised to 2^32 - 1.
  std::vector<std::uint8_t> image = messages[0].second;
  std::memset(image.data() + image.size() - 24 - 4, 0xff, 4);
  EXPECT_FALSE(ros1::detail::lengthsFit("sensor_msgs/Image", image.data(), image.size()));
  // The transform count raised to 2^32 - 1: roscpp would resize to 4 G transforms.
  std::vector<std::uint8_t> many = messages[3].second;
  std::memset(many.data(), 0xff, 4);
  EXPECT_FALSE(ros1::detail::lengthsFit("tf2_msgs/TFMessage", many.data(), many.size()));
  EXPECT_TRUE(ros1::detail::lengthsFit("std_msgs/String", nullptr, 0));  // not walked
}

// A BZ2 chunk whose header claims 10^9 bytes of data: damage naming them, found with the pages the
// decompressor wrote, not a gigabyte of zeroes first (the peak resident memory of this test's
// process; not measured under ASan, whose allocator differs).
TEST(BagDamageMemory, ChunkClaimingAGigabyteCostsWhatItHolds) {
  const test::TempDir dir("bag_claim");
  std::string bytes = writeBag(dir.file("good.bag"), rosbag::compression::BZ2);
  const std::size_t chunk = bytes.find("compression=bz2");
  ASSERT_NE(chunk, std::string::npos);
  const std::size_t size_field = bytes.find("size=", chunk);
  ASSERT_NE(size_field, std::string::npos);
  const std::uint32_t claim = 1'000'000'000;
  std::memcpy(&bytes[size_field + 5], &claim, 4);
  const std::string bad = dir.file("bad.bag");
  write(bad, bytes);
  rusage before{};
  getrusage(RUSAGE_SELF, &before);
  std::string error;
  ASSERT_EQ(framesOf(bad, error), -1);
  EXPECT_NE(error.find("does not decompress to its 1000000000 bytes"), std::string::npos) << error;
#ifndef UPD_TEST_UNDER_ASAN
  rusage after{};
  getrusage(RUSAGE_SELF, &after);
  EXPECT_LT(after.ru_maxrss - before.ru_maxrss, 256 * 1024) << "kB more at the peak";
#endif
}

// A connection whose type names another message than its MD5 sum does (found by fuzz_bag: the
// sum of PointCloud2, the name CompressedImage): the reader takes a message by its MD5 sum, as
// rosbag does, so its lengths are walked by the layout of the type it is read as. A point
// cloud's field count raised to 2^32 - 1 is found there, not allocated (~200 GB); walked as the
// type named, the same bytes fit.
TEST(BagMessages, AreWalkedByTheTypeTheyAreReadAs) {
  const test::TempDir dir("bag_type");
  const std::string path = dir.file("run.bag");
  {
    rosbag::Bag bag(path, rosbag::bagmode::Write);
    core::PointCloud cloud;
    cloud.push_back(1.f, 0.f, 0.f);
    sensor_msgs::PointCloud2 points = ros1::pointCloud2FromCloud(cloud);
    points.header.frame_id = "fields_follow";
    points.height = 0;  // so that the bytes walked as a CompressedImage fit (an empty format)
    const auto header = boost::make_shared<ros::M_string>(ros::M_string{
        {"callerid", "/recorder"},
        {"type", "sensor_msgs/CompressedImage"},
        {"md5sum", ros::message_traits::md5sum(points)},
        {"message_definition", ros::message_traits::definition(points)}});
    bag.write("/points", ros::Time(1.0), points, header);
  }
  std::ifstream in(path, std::ios::binary);
  std::string bytes(std::istreambuf_iterator<char>(in), {});
  const std::size_t at = bytes.find("fields_follow");
  ASSERT_NE(at, std::string::npos);
  std::memset(&bytes[at + 13 + 8], 0xff, 4);  // after the frame id: height, width, the field count
  write(path, bytes);
  const ros1::BagReadStats stats = ros1::readBag(path, {}, [](const ros1::BagFrame&) {});
  ASSERT_EQ(stats.skipped.size(), 1u);
  EXPECT_EQ(stats.skipped.begin()->first,
            "a message on /points that does not deserialize (a length runs past its data)");
}

INSTANTIATE_TEST_SUITE_P(Compressions, BagDamage,
                         ::testing::Values(rosbag::compression::Uncompressed,
                                           rosbag::compression::BZ2, rosbag::compression::LZ4),
                         [](const auto& p) { return test::compressionName(p.param); });

}  // namespace
