// PCD through PCL: every shared .pcd with x/y/z loads with the documented size, layout and
// colour; a file without x/y/z and truncated or corrupt copies fail cleanly; writePcd round
// trips (organized, NaN, colour, viewpoint).
#include "io_test_util.h"
#include "upd/io/cloud_io.h"
#include "error_of.h"

#include "test_data.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>

namespace core = upd::core;

namespace {

namespace fs = std::filesystem;
using upd::core::PointCloud;

using upd::test::TempDir;

using upd::test::readBytes;

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string errorOf(const std::string& path) {
  return upd::test::errorOf<std::runtime_error>([&] { upd::io::readCloud(path); });
}

bool anyColour(const core::PointCloud& c) {
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (c.r[i] != 0 || c.g[i] != 0 || c.b[i] != 0) return true;
  }
  return false;
}

TEST(PcdShared, Office1OrganizedWithColour) {
  UPD_REQUIRE_SHARED_FILE(f, "pcl/office1.pcd");
  const core::PointCloud c = upd::io::readCloud(f);
  EXPECT_TRUE(c.isOrganized());
  EXPECT_EQ(c.width, 640u);
  EXPECT_EQ(c.height, 480u);
  EXPECT_EQ(c.size(), 307200u);
  EXPECT_EQ(c.countFinite(), 254456u);
  ASSERT_TRUE(c.hasColor());
  EXPECT_TRUE(anyColour(c));
  EXPECT_EQ(c.sensor_origin, Eigen::Vector3f::Zero());
  // cam-optical frame: depth (z) of the finite points is 1.8-5.4 m (SOURCES.md).
  float zmin = 1e9f, zmax = -1e9f;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!c.isFinite(i)) continue;
    zmin = std::min(zmin, c.z[i]);
    zmax = std::max(zmax, c.z[i]);
  }
  EXPECT_GT(zmin, 1.5f);
  EXPECT_LT(zmax, 6.0f);
}

TEST(PcdShared, RegionGrowingTutorial) {
  UPD_REQUIRE_SHARED_FILE(f, "pcl-data/region_growing_rgb_tutorial.pcd");
  const core::PointCloud c = upd::io::readCloud(f);
  EXPECT_TRUE(c.isOrganized());
  EXPECT_EQ(c.width, 640u);
  EXPECT_EQ(c.height, 480u);
  EXPECT_EQ(c.countFinite(), 259847u);
  ASSERT_TRUE(c.hasColor());
  EXPECT_TRUE(anyColour(c));
}

TEST(PcdShared, TableSceneMugRgba) {
  UPD_REQUIRE_SHARED_FILE(f, "pcl/table_scene_mug_stereo_textured.pcd");
  const core::PointCloud c = upd::io::readCloud(f);
  EXPECT_TRUE(c.isOrganized());
  EXPECT_EQ(c.size(), 640u * 480u);
  EXPECT_EQ(c.countFinite(), 209280u);
  ASSERT_TRUE(c.hasColor());
  EXPECT_TRUE(anyColour(c));
}

TEST(PcdShared, StairPerceptionBinaryRgba) {
  UPD_REQUIRE_SHARED_FILE(f, "stair-perception/0000_cloud.pcd");
  const core::PointCloud c = upd::io::readCloud(f);
  EXPECT_TRUE(c.isOrganized());
  EXPECT_EQ(c.width, 512u);
  EXPECT_EQ(c.height, 424u);
  EXPECT_EQ(c.countFinite(), c.size());  // no NaN in this file (SOURCES.md)
  ASSERT_TRUE(c.hasColor());
  EXPECT_TRUE(anyColour(c));
}

TEST(PcdShared, FastGicpLidarWithIntensity) {
  UPD_REQUIRE_SHARED_FILE(f, "fast_gicp/251370668.pcd");
  const core::PointCloud c = upd::io::readCloud(f);
  EXPECT_FALSE(c.isOrganized());
  EXPECT_EQ(c.size(), 69088u);
  EXPECT_EQ(c.width, 69088u);
  EXPECT_EQ(c.height, 1u);
  EXPECT_FALSE(c.hasColor());  // intensity is not colour
  std::size_t zeros = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    zeros += (c.x[i] == 0.f && c.y[i] == 0.f && c.z[i] == 0.f) ? 1 : 0;
  }
  EXPECT_EQ(zeros, 5032u);
}

TEST(PcdShared, Samp11Terrain) {
  UPD_REQUIRE_SHARED_FILE(f, "pcl-data/samp11-utm.pcd");
  const core::PointCloud c = upd::io::readCloud(f);
  EXPECT_EQ(c.size(), 38010u);
  EXPECT_EQ(c.countFinite(), 38010u);
  EXPECT_FALSE(c.hasColor());
  // Absolute UTM coordinates (SOURCES.md): northing ~5.4e6, easting ~5.1e5.
  EXPECT_GT(c.y[0], 5.0e6f);
  EXPECT_GT(c.x[0], 4.0e5f);
}

TEST(PcdShared, Samp11Ground) {
  UPD_REQUIRE_SHARED_FILE(f, "pcl-data/samp11-utm-ground.pcd");
  EXPECT_EQ(upd::io::readCloud(f).size(), 21786u);
}

TEST(PcdShared, StereoImageWithoutXyzFails) {
  UPD_REQUIRE_SHARED_FILE(f, "pcl/stereo_left.pcd");
  const std::string msg = errorOf(f);
  EXPECT_NE(msg.find("x/y/z"), std::string::npos) << msg;
  EXPECT_NE(msg.find(f), std::string::npos) << msg;
  EXPECT_NE(msg.find("rgba"), std::string::npos) << msg;
}

TEST(PcdShared, TruncatedCopiesFailWithFileName) {
  TempDir dir;
  for (const char* rel : {"pcl/office1.pcd", "stair-perception/0000_cloud.pcd"}) {
    const std::string src = upd::test::sharedFile(rel);
    if (src.empty()) GTEST_SKIP() << rel << " not found under " << upd::test::sharedDataDir();
    const std::string bytes = readBytes(src);
    // Not size - 1: PCL pads binary files to a page, so the last bytes may be padding.
    for (const std::size_t keep : {bytes.size() / 2, bytes.size() * 9 / 10, std::size_t{300}}) {
      const std::string f = dir.file("cut_" + std::to_string(keep) + ".pcd");
      writeBytes(f, bytes.substr(0, keep));
      const std::string msg = errorOf(f);
      EXPECT_NE(msg.find(f), std::string::npos) << rel << " cut at " << keep << ": " << msg;
    }
  }
}

TEST(PcdIo, CorruptCompressedBlockFails) {
  UPD_REQUIRE_SHARED_FILE(src, "pcl/office1.pcd");
  TempDir dir;
  std::string bytes = readBytes(src);
  const std::size_t data = bytes.find("DATA binary_compressed\n") + 23;
  // Claim a larger uncompressed size than the header's points need.
  bytes[data + 4] = static_cast<char>(0x7f);
  const std::string f = dir.file("corrupt.pcd");
  writeBytes(f, bytes);
  const std::string msg = errorOf(f);
  EXPECT_NE(msg.find(f), std::string::npos) << msg;
}

TEST(PcdIo, GarbageAndEmptyFilesFail) {
  TempDir dir;
  const std::string g = dir.file("garbage.pcd");
  writeBytes(g, std::string(1000, '\x01'));
  EXPECT_NE(errorOf(g).find(g), std::string::npos);
  const std::string e = dir.file("empty.pcd");
  writeBytes(e, "");
  EXPECT_NE(errorOf(e).find(e), std::string::npos);
}

// A header whose point count asks PCL for terabytes (what fuzz_pcd found: PCL's readHeader
// allocates POINTS x the point's bytes before it reads the body) is refused before PCL reads it,
// naming the count; a count the file can hold is read as before.
TEST(PcdIo, PointCountTheFileCannotHoldFailsBeforePclAllocates) {
  TempDir dir;
  const std::string header_head =
      "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  const std::string huge = dir.file("huge.pcd");
  writeBytes(huge, header_head + "WIDTH 51539607552\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
                                 "POINTS 51539607552\nDATA binary\n" + std::string(24, '\0'));
  const std::string msg = errorOf(huge);
  EXPECT_NE(msg.find(huge), std::string::npos) << msg;
  EXPECT_NE(msg.find("POINTS 51539607552"), std::string::npos) << msg;

  // A negative SIZE, which PCL sums as unsigned into 4 GB a point (the input fuzz_pcd found).
  const std::string negative = dir.file("negative.pcd");
  writeBytes(negative, "VERSION .7\nFIELDS x y z\nSIZE 4 -4 4\nTYPE F F F\nCOUNT 1 4 1\n"
                       "WIDTH 1\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 2 3\n");
  const std::string neg_msg = errorOf(negative);
  EXPECT_NE(neg_msg.find(negative), std::string::npos) << neg_msg;
  EXPECT_NE(neg_msg.find("SIZE 4 -4 4"), std::string::npos) << neg_msg;

  const std::string two = dir.file("two.pcd");
  writeBytes(two, header_head + "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\n"
                                "DATA ascii\n1 2 3\n4 5 6\n");
  const core::PointCloud c = upd::io::readCloud(two);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.z[1], 6.f);
}

// PCL finds a header line by the first letters of its first word and reads the count after it
// as an istream does (a sign, digits, the rest ignored; "-1" and a count past the range read as
// the largest number): each of these asks PCL for more than the file can hold, and is refused
// naming the count PCL would read, before PCL allocates (fuzz_pcd found the first two).
TEST(PcdIo, PointCountIsReadAsPclReadsIt) {
  TempDir dir;
  const std::string head = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                           "WIDTH 1\nHEIGHT 1\n";
  const std::string max = std::to_string(std::numeric_limits<std::uint64_t>::max());
  const std::pair<std::string, std::string> cases[] = {
      {"POINTS 6666666666# .PCD v0.7", "POINTS 6666666666 "},
      {"POINTSX 6666666666", "POINTS 6666666666 "},
      {"  POINTS\t+6666666666 7", "POINTS 6666666666 "},
      {"POINTS -1", "POINTS " + max},
      {"POINTS 99999999999999999999", "POINTS " + max},
  };
  int i = 0;
  for (const auto& [points_line, expected] : cases) {
    const std::string path = dir.file("count" + std::to_string(i++) + ".pcd");
    writeBytes(path, head + points_line + "\nDATA ascii\n1 2 3\n");
    const std::string msg = errorOf(path);
    EXPECT_NE(msg.find(path), std::string::npos) << points_line << ": " << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << points_line << ": " << msg;
  }
  // A count followed by a comment, as PCL reads it, is read.
  const std::string ok = dir.file("ok.pcd");
  writeBytes(ok, head + "POINTS 1 # one point\nDATA ascii\n1 2 3\n");
  EXPECT_EQ(upd::io::readCloud(ok).size(), 1u);
}

// PCL reads header lines on after the DATA line, up to the first line that is not one (and
// skips blank lines and comments on the way): a count there, or a FIELDS line that widens the
// point, is PCL's too (fuzz_pcd found the first). A line before DATA that is no header line
// ends PCL's header there, so such a file is refused, its line shown as text.
TEST(PcdIo, HeaderLinesAfterTheDataLineAreReadAsPclReadsThem) {
  TempDir dir;
  const std::string head = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                           "WIDTH 1\nHEIGHT 1\nPOINTS 1\n";
  std::string manyFields;  // 5,000 fields of 4 bytes: 20,000 bytes a point
  for (int f = 0; f < 5000; ++f) manyFields += " a";
  const std::pair<std::string, std::string> cases[] = {
      {"DATA ascii\nPOINTS 6666666666\n1 2 3\n", "POINTS 6666666666 "},
      {"DATA ascii\n\n# a comment\n\v POINTS 6666666666\n1 2 3\n", "POINTS 6666666666 "},
      {"DATA ascii\nCOLUMNS" + manyFields + "\nPOINTS 2000\n1 2 3\n", "POINTS 2000 "},
      {"UNKNOWN \x01\x02 line\nDATA ascii\n1 2 3\n", "line 9 ('UNKNOWN ?? line') is not a header line"},
  };
  int i = 0;
  for (const auto& [tail, expected] : cases) {
    const std::string path = dir.file("after" + std::to_string(i++) + ".pcd");
    writeBytes(path, head + tail);
    const std::string msg = errorOf(path);
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\x01'), std::string::npos) << msg;
  }
  // The body's first line ends the header: a file whose later body lines spell a keyword is read.
  const std::string ok = dir.file("ok.pcd");
  writeBytes(ok, head + "DATA ascii\n1 2 3\n");
  EXPECT_EQ(upd::io::readCloud(ok).size(), 1u);
}

TEST(PcdIo, AsciiPcdWithViewpointAndDoubleCoordinates) {
  TempDir dir;
  const std::string f = dir.file("ascii.pcd");
  writeBytes(f,
             "# .PCD v0.7 - Point Cloud Data file format\n"
             "VERSION 0.7\n"
             "FIELDS x y z intensity\n"
             "SIZE 8 8 8 4\n"
             "TYPE F F F F\n"
             "COUNT 1 1 1 1\n"
             "WIDTH 3\n"
             "HEIGHT 1\n"
             "VIEWPOINT 1 2 3 1 0 0 0\n"
             "POINTS 3\n"
             "DATA ascii\n"
             "0.5 1.5 2.5 9\n"
             "nan nan nan 0\n"
             "-1 -2 -3 4\n");
  const core::PointCloud c = upd::io::readCloud(f);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_FALSE(c.hasColor());
  EXPECT_EQ(c.x[0], 0.5f);
  EXPECT_EQ(c.z[0], 2.5f);
  EXPECT_TRUE(std::isnan(c.x[1]));
  EXPECT_EQ(c.z[2], -3.f);
  EXPECT_EQ(c.sensor_origin, Eigen::Vector3f(1, 2, 3));
}

TEST(PcdIo, DamagedAsciiPcdFailsInsteadOfReadingZero) {
  TempDir dir;
  const std::string header =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\n"
      "POINTS 3\nDATA ascii\n";
  const std::string bad_number = dir.file("bad_number.pcd");
  writeBytes(bad_number, header + "1 2 3\n4 five 6\n7 8 9\n");
  std::string msg = errorOf(bad_number);
  EXPECT_NE(msg.find(bad_number), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 11"), std::string::npos) << msg;
  EXPECT_NE(msg.find("five"), std::string::npos) << msg;

  const std::string short_line = dir.file("short_line.pcd");
  writeBytes(short_line, header + "1 2 3\n4 6\n7 8 9\n");
  msg = errorOf(short_line);
  EXPECT_NE(msg.find("line 11"), std::string::npos) << msg;

  const std::string truncated = dir.file("truncated.pcd");
  writeBytes(truncated, header + "1 2 3\n4 5 6\n");
  msg = errorOf(truncated);
  EXPECT_NE(msg.find(truncated), std::string::npos) << msg;
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
}

TEST(PcdIo, WriteReadRoundTripOrganizedWithColour) {
  TempDir dir;
  core::PointCloud c;
  c.resizeOrganized(4, 3);
  c.r.assign(12, 0);
  c.g.assign(12, 0);
  c.b.assign(12, 0);
  for (std::size_t i = 0; i < 12; ++i) {
    if (i == 5) continue;  // stays NaN
    c.x[i] = 0.1f * static_cast<float>(i);
    c.y[i] = -2.f + static_cast<float>(i);
    c.z[i] = 1e3f / static_cast<float>(i + 1);
    c.r[i] = static_cast<std::uint8_t>(20 * i);
    c.g[i] = static_cast<std::uint8_t>(255 - i);
    c.b[i] = static_cast<std::uint8_t>(i);
  }
  c.sensor_origin = Eigen::Vector3f(0.5f, -1.f, 2.f);
  const std::string f = dir.file("round.pcd");
  upd::io::writePcd(f, c);
  const core::PointCloud back = upd::io::readCloud(f);
  ASSERT_EQ(back.size(), 12u);
  EXPECT_EQ(back.width, 4u);
  EXPECT_EQ(back.height, 3u);
  ASSERT_TRUE(back.hasColor());
  EXPECT_EQ(back.sensor_origin, c.sensor_origin);
  for (std::size_t i = 0; i < 12; ++i) {
    if (i == 5) {
      EXPECT_FALSE(back.isFinite(i));
      continue;
    }
    EXPECT_EQ(back.x[i], c.x[i]);
    EXPECT_EQ(back.y[i], c.y[i]);
    EXPECT_EQ(back.z[i], c.z[i]);
    EXPECT_EQ(back.r[i], c.r[i]);
    EXPECT_EQ(back.g[i], c.g[i]);
    EXPECT_EQ(back.b[i], c.b[i]);
  }

  core::PointCloud plain;
  plain.push_back(1, 2, 3);
  plain.push_back(4, 5, 6);
  upd::io::writePcd(f, plain);  // overwrites atomically
  const core::PointCloud p = upd::io::readPcd(f);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_FALSE(p.hasColor());
  EXPECT_FALSE(p.isOrganized());
  EXPECT_EQ(p.y[1], 5.f);
}

}  // namespace
