// XYZ text: comments, commas, blank lines, a column header, colour columns, exact round trips,
// and errors that name the file and line.
#include "io_test_util.h"
#include "upd/io/cloud_io.h"
#include "error_of.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

namespace core = upd::core;

namespace {

namespace fs = std::filesystem;
using upd::core::PointCloud;

using upd::test::TempDir;

void writeText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::string errorOf(const std::string& path) {
  return upd::test::errorOf<std::runtime_error>([&] { upd::io::readCloud(path); });
}

TEST(XyzIo, CommentsCommasBlankLinesAndHeader) {
  TempDir dir;
  const std::string f = dir.file("points.xyz");
  writeText(f,
            "# exported by hand\n"
            "X,Y,Z\n"
            "\n"
            "1, 2, 3\n"
            "  4\t5   6   # trailing comment\r\n"
            "-7.5e-1,+8,nan\n"
            "   # indented comment\n"
            "9 10 11");  // no final newline
  const core::PointCloud c = upd::io::readCloud(f);
  ASSERT_EQ(c.size(), 4u);
  EXPECT_FALSE(c.hasColor());
  EXPECT_EQ(c.x[0], 1.f);
  EXPECT_EQ(c.z[0], 3.f);
  EXPECT_EQ(c.y[1], 5.f);
  EXPECT_EQ(c.x[2], -0.75f);
  EXPECT_EQ(c.y[2], 8.f);
  EXPECT_TRUE(std::isnan(c.z[2]));
  EXPECT_EQ(c.z[3], 11.f);
  EXPECT_EQ(c.width, 4u);
  EXPECT_EQ(c.height, 1u);
}

TEST(XyzIo, ColourColumns) {
  TempDir dir;
  const std::string f = dir.file("colour.TXT");
  writeText(f, "0 0 0 255 128 0\n1,1,1,1,2,3\n");
  const core::PointCloud c = upd::io::readCloud(f);
  ASSERT_EQ(c.size(), 2u);
  ASSERT_TRUE(c.hasColor());
  EXPECT_EQ(c.r[0], 255);
  EXPECT_EQ(c.g[0], 128);
  EXPECT_EQ(c.b[0], 0);
  EXPECT_EQ(c.b[1], 3);
}

TEST(XyzIo, BadLinesNameFileAndLine) {
  TempDir dir;
  const std::string a = dir.file("bad_number.xyz");
  writeText(a, "# c\n1 2 3\n\n4 x5 6\n");
  std::string msg = errorOf(a);
  EXPECT_NE(msg.find(a), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("x5"), std::string::npos) << msg;

  const std::string b = dir.file("columns.xyz");
  writeText(b, "1 2 3\n4 5 6 7 8 9\n");
  msg = errorOf(b);
  EXPECT_NE(msg.find(b), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;

  const std::string c = dir.file("four.xyz");
  writeText(c, "1 2 3 4\n");
  msg = errorOf(c);
  EXPECT_NE(msg.find("line 1"), std::string::npos) << msg;

  const std::string d = dir.file("colour_range.xyz");
  writeText(d, "1 2 3 0 0 0\n1 2 3 0 256 0\n");
  msg = errorOf(d);
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;
  EXPECT_NE(msg.find("0..255"), std::string::npos) << msg;
}

TEST(XyzIo, EmptyFileIsAnEmptyCloud) {
  TempDir dir;
  const std::string f = dir.file("empty.xyz");
  writeText(f, "# nothing here\n\n");
  EXPECT_TRUE(upd::io::readXyz(f).empty());
}

TEST(XyzIo, WriteReadRoundTripIsExact) {
  TempDir dir;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> coord(-1e4f, 1e4f);
  for (const bool colour : {false, true}) {
    core::PointCloud c;
    for (int i = 0; i < 2000; ++i) {
      if (colour) {
        c.push_back(coord(rng), coord(rng), coord(rng) * 1e-6f, static_cast<std::uint8_t>(i),
                    static_cast<std::uint8_t>(255 - i % 256), 7);
      } else {
        c.push_back(coord(rng), coord(rng), coord(rng) * 1e-6f);
      }
    }
    c.x[5] = std::numeric_limits<float>::quiet_NaN();
    const std::string f = dir.file(colour ? "c.xyz" : "p.xyz");
    upd::io::writeXyz(f, c);
    const core::PointCloud back = upd::io::readXyz(f);
    ASSERT_EQ(back.size(), c.size());
    ASSERT_EQ(back.hasColor(), colour);
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (i == 5) {
        EXPECT_TRUE(std::isnan(back.x[i]));
      } else {
        ASSERT_EQ(back.x[i], c.x[i]) << i;
      }
      ASSERT_EQ(back.y[i], c.y[i]) << i;
      ASSERT_EQ(back.z[i], c.z[i]) << i;
      if (colour) {
        ASSERT_EQ(back.r[i], c.r[i]);
        ASSERT_EQ(back.g[i], c.g[i]);
        ASSERT_EQ(back.b[i], c.b[i]);
      }
    }
  }
}

TEST(CloudIo, UnknownExtensionNamesFileAndSupportedOnes) {
  TempDir dir;
  const std::string f = dir.file("cloud.las");
  writeText(f, "whatever");
  const std::string msg = errorOf(f);
  EXPECT_NE(msg.find(f), std::string::npos) << msg;
  for (const char* ext : {".pcd", ".ply", ".xyz", ".txt"}) {
    EXPECT_NE(msg.find(ext), std::string::npos) << msg;
  }
  EXPECT_NE(errorOf(dir.file("no_extension")).find("supported"), std::string::npos);
}

TEST(CloudIo, MissingFileAndDirectory) {
  TempDir dir;
  for (const char* name : {"missing.pcd", "missing.ply", "missing.xyz"}) {
    const std::string f = dir.file(name);
    const std::string msg = errorOf(f);
    EXPECT_NE(msg.find(f), std::string::npos) << msg;
    EXPECT_NE(msg.find("not found"), std::string::npos) << msg;
  }
  const std::string d = dir.file("folder.ply");
  fs::create_directory(d);
  EXPECT_NE(errorOf(d).find("directory"), std::string::npos);
}

TEST(CloudIo, LowerExtension) {
  EXPECT_EQ(upd::io::lowerExtension("/a/b.c/Cloud.PcD"), ".pcd");
  EXPECT_EQ(upd::io::lowerExtension("/a/b.c/cloud"), "");
  EXPECT_EQ(upd::io::lowerExtension("x.tar.PLY"), ".ply");
}

}  // namespace
