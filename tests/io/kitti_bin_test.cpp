// KITTI .bin scans and SemanticKITTI labels: exact round trips (NaN, Inf and 1e30 kept as they
// are), and every damaged or foreign file refused with a message naming the file and what is
// wrong, the size for a truncated scan.
#include "io_test_util.h"

#include "upd/io/cloud_io.h"
#include "upd/io/kitti_bin.h"
#include "error_of.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>

namespace {

using upd::test::readBytes;
using upd::test::TempDir;

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string errorOf(const std::function<void()>& f) {
  return upd::test::errorOf<std::runtime_error>(f);
}

upd::core::PointCloud sampleCloud() {
  upd::core::PointCloud c;
  c.push_back(1.5f, -2.25f, 0.125f);
  c.push_back(std::numeric_limits<float>::quiet_NaN(), 0.f, 1.f);
  c.push_back(std::numeric_limits<float>::infinity(), 1e30f, -1e30f);
  return c;
}

TEST(KittiBin, RoundTripIsBitExact) {
  TempDir dir;
  const std::string f = dir.file("000000.bin");
  const upd::core::PointCloud c = sampleCloud();
  upd::io::writeKittiBin(f, c, {0.5f, 0.f, 1.f});
  EXPECT_EQ(readBytes(f).size(), 3u * 16u);
  const upd::io::KittiScan s = upd::io::readKittiBin(f);
  ASSERT_EQ(s.cloud.size(), 3u);
  EXPECT_EQ(std::memcmp(s.cloud.x.data(), c.x.data(), 12), 0);
  EXPECT_EQ(std::memcmp(s.cloud.y.data(), c.y.data(), 12), 0);
  EXPECT_EQ(std::memcmp(s.cloud.z.data(), c.z.data(), 12), 0);
  EXPECT_EQ(s.intensity, (std::vector<float>{0.5f, 0.f, 1.f}));
  EXPECT_FALSE(s.cloud.isOrganized());
  EXPECT_EQ(upd::io::readCloud(f).size(), 3u);  // .bin goes to the KITTI reader
}

TEST(KittiBin, LayoutIsLittleEndianXyzIntensity) {
  TempDir dir;
  const std::string f = dir.file("one.bin");
  // 1.0f = 0x3f800000, 2.0f = 0x40000000, -1.0f = 0xbf800000, 0.5f = 0x3f000000
  writeBytes(f, std::string("\x00\x00\x80\x3f\x00\x00\x00\x40\x00\x00\x80\xbf\x00\x00\x00\x3f", 16));
  const upd::io::KittiScan s = upd::io::readKittiBin(f);
  ASSERT_EQ(s.cloud.size(), 1u);
  EXPECT_EQ(s.cloud.point(0), Eigen::Vector3f(1.f, 2.f, -1.f));
  EXPECT_EQ(s.intensity[0], 0.5f);
}

TEST(KittiBin, EmptyFileIsAScanOfNoPoints) {
  TempDir dir;
  writeBytes(dir.file("empty.bin"), "");
  EXPECT_TRUE(upd::io::readKittiBin(dir.file("empty.bin")).cloud.empty());
}

TEST(KittiBin, TruncatedScanNamesFileAndSize) {
  TempDir dir;
  upd::io::writeKittiBin(dir.file("whole.bin"), sampleCloud());
  const std::string whole = readBytes(dir.file("whole.bin"));
  const std::string f = dir.file("cut.bin");
  for (std::size_t keep : {1u, 15u, 17u, 47u}) {
    writeBytes(f, whole.substr(0, keep));
    const std::string msg = errorOf([&] { upd::io::readKittiBin(f); });
    EXPECT_NE(msg.find(f), std::string::npos) << msg;
    EXPECT_NE(msg.find(std::to_string(keep) + " bytes is not a whole number of 16-byte points"),
              std::string::npos)
        << msg;
  }
}

TEST(KittiBin, OtherFormatsUnderTheBinExtensionAreNamed) {
  TempDir dir;
  const struct {
    const char* content;
    const char* says;
  } cases[] = {{"ply\nformat ascii 1.0\nelement vertex 0\nend_header\n", "is a PLY file"},
               {"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\n",
                "is a PCD file"},
               {"VERSION .7\nFIELDS x y z\nSIZE 4 4 4\n", "is a PCD file"},
               {"1.0 2.0 3.0\n4.0 5.0 6.0\n", "is text"},
               {"\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03\x00\x00\x00\x00\x00\x00",
                "is gzip-compressed data"}};
  for (const auto& c : cases) {
    const std::string f = dir.file("scan.bin");
    writeBytes(f, std::string(c.content, std::strlen(c.content) ? std::strlen(c.content) : 16));
    const std::string msg = errorOf([&] { upd::io::readCloud(f); });
    EXPECT_NE(msg.find(f), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.says), std::string::npos) << c.content << " -> " << msg;
  }
}

TEST(KittiBin, MissingFileAndDirectory) {
  TempDir dir;
  EXPECT_NE(errorOf([&] { upd::io::readKittiBin(dir.file("none.bin")); }).find("not found"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { upd::io::readKittiBin(dir.path().string()); }).find("directory"),
            std::string::npos);
}

TEST(SemanticKittiLabels, ReadsClassAndInstance) {
  TempDir dir;
  const std::string f = dir.file("000000.label");
  // class 40 (road), instance 0; class 10 (car), instance 7
  writeBytes(f, std::string("\x28\x00\x00\x00\x0a\x00\x07\x00", 8));
  const auto labels = upd::io::readSemanticKittiLabels(f, 2);
  ASSERT_EQ(labels.size(), 2u);
  EXPECT_EQ(upd::io::semanticClassOf(labels[0]), 40);
  EXPECT_EQ(upd::io::semanticClassOf(labels[1]), 10);
  EXPECT_EQ(labels[1] >> 16, 7u);
  const std::string mismatch = errorOf([&] { upd::io::readSemanticKittiLabels(f, 3); });
  EXPECT_NE(mismatch.find("2 labels for a scan of 3 points"), std::string::npos) << mismatch;
  writeBytes(f, std::string("\x28\x00\x00", 3));
  const std::string cut = errorOf([&] { upd::io::readSemanticKittiLabels(f); });
  EXPECT_NE(cut.find("truncated SemanticKITTI .label file: 3 bytes"), std::string::npos) << cut;
}

}  // namespace
