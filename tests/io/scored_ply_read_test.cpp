// readScoredPly: the scored PLY read back through readPly's parser, whatever encoding or scalar
// types another tool re-saved it with, and a file that is not a scored PLY refused by name.
#include "io_test_util.h"
#include "upd/io/cloud_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

namespace core = upd::core;
using core::Label;
using upd::test::TempDir;

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

// Equal as stored: the same bits for numbers, NaN for NaN.
void expectSameFloats(const std::vector<float>& a, const std::vector<float>& b, const char* what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(a[i])) {
      EXPECT_TRUE(std::isnan(b[i])) << what << " " << i;
    } else {
      EXPECT_EQ(a[i], b[i]) << what << " " << i;
    }
  }
}

// A pipeline result written by writeScoredPly (with its sensor origin) and read back.
TEST(ScoredPlyRead, GivesBackWhatWriteScoredPlyWrote) {
  const TempDir dir;
  core::PipelineResult res;
  core::PointCloud& c = res.cloud;
  c.resize(4, true);
  c.sensor_origin = Eigen::Vector3f(0.5f, 0.f, 1.25f);
  for (std::size_t i = 0; i < 4; ++i) {
    c.x[i] = 0.5f * i - 1.f;
    c.y[i] = 2.f - i;
    c.z[i] = 0.125f * i;
    c.r[i] = static_cast<std::uint8_t>(60 * i);
    c.g[i] = 7;
    c.b[i] = static_cast<std::uint8_t>(255 - i);
  }
  res.normals.nx = {0.f, 0.1f, kNan, 0.f};
  res.normals.ny = {0.f, 0.2f, kNan, 1.f};
  res.normals.nz = {1.f, 0.97f, kNan, 0.f};
  res.upd.rx = {0.5f, -1.f, kNan, 2.f};
  res.upd.ry = {0.f, 3.f, kNan, 0.25f};
  res.upd.rz = {17.f, 9.5f, kNan, 1.f};
  res.upd.zeta = {0.999f, 0.72f, kNan, 0.95f};
  res.classes.cost = {0.f, 1.f, kNan, 0.5f};
  res.classes.label = {Label::Traversable, Label::NonTraversable, Label::Unknown,
                       Label::Traversable};
  const std::string f = dir.file("scored.ply");
  upd::io::writeScoredPly(f, res);

  const upd::io::ScoredPly s = upd::io::readScoredPly(f);
  expectSameFloats(s.cloud.x, c.x, "x");
  expectSameFloats(s.cloud.z, c.z, "z");
  EXPECT_EQ(s.cloud.r, c.r);
  EXPECT_EQ(s.cloud.b, c.b);
  EXPECT_EQ(s.cloud.sensor_origin, c.sensor_origin);
  expectSameFloats(s.nx, res.normals.nx, "nx");
  expectSameFloats(s.nz, res.normals.nz, "nz");
  expectSameFloats(s.rx, res.upd.rx, "rx");
  expectSameFloats(s.ry, res.upd.ry, "ry");
  expectSameFloats(s.rz, res.upd.rz, "rz");
  expectSameFloats(s.zeta, res.upd.zeta, "zeta");
  expectSameFloats(s.cost, res.classes.cost, "cost");
  EXPECT_EQ(s.label, res.classes.label);
  EXPECT_EQ(upd::io::plyVertexProperties(f).size(), upd::io::scoredPlyProperties().size() + 3);
}

// The same two vertices as ascii and as big-endian doubles, without r and with labels written
// as floats (a tool that re-saves every scalar field as float or double).
TEST(ScoredPlyRead, AsciiAndBigEndianCopiesReadTheSame) {
  const TempDir dir;
  const std::string header_props =
      "property double x\nproperty double y\nproperty double z\nproperty double nx\n"
      "property double ny\nproperty double nz\nproperty double scalar_zeta\n"
      "property double scalar_label\nproperty double scalar_cost\nend_header\n";
  const double rows[2][9] = {{1.5, -2.25, 0.125, 0, 0, 1, 0.99, 0, 0.1},
                             {2.0, 0.0, 0.0, 0, 0.6, 0.8, 0.71, 1, 0.9}};
  const std::string ascii = dir.file("ascii.ply");
  {
    std::ofstream out(ascii);
    out << "ply\nformat ascii 1.0\nelement vertex 2\n" << header_props;
    for (const auto& r : rows) {
      for (double v : r) out << v << ' ';
      out << '\n';
    }
  }
  const std::string big = dir.file("big.ply");
  {
    std::ofstream out(big, std::ios::binary);
    out << "ply\nformat binary_big_endian 1.0\nelement vertex 2\n" << header_props;
    for (const auto& r : rows) {
      for (double v : r) {
        unsigned char b[8];
        std::memcpy(b, &v, 8);
        for (int k = 7; k >= 0; --k) out.put(static_cast<char>(b[k]));
      }
    }
  }
  for (const std::string& f : {ascii, big}) {
    const upd::io::ScoredPly s = upd::io::readScoredPly(f);
    ASSERT_EQ(s.cloud.size(), 2u) << f;
    EXPECT_EQ(s.cloud.x[0], 1.5f) << f;
    EXPECT_EQ(s.cloud.y[0], -2.25f) << f;
    EXPECT_EQ(s.ny[1], 0.6f) << f;
    EXPECT_EQ(s.zeta[1], 0.71f) << f;
    EXPECT_EQ(s.cost[0], 0.1f) << f;
    EXPECT_EQ(s.label, (std::vector<Label>{Label::Traversable, Label::NonTraversable})) << f;
    EXPECT_TRUE(std::isnan(s.rx[0]) && std::isnan(s.rz[1])) << f << ": absent r is NaN";
    EXPECT_FALSE(s.cloud.hasColor()) << f;
  }
}

TEST(ScoredPlyRead, ARawCloudIsRefusedNamingTheMissingProperty) {
  const TempDir dir;
  core::PointCloud c;
  c.resize(2, false);
  const std::string f = dir.file("raw.ply");
  upd::io::writePly(f, c);
  try {
    upd::io::readScoredPly(f);
    ADD_FAILURE() << "a raw cloud read as scored";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'" + f + "': not a scored PLY: no vertex property 'nx'"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(upd::io::plyVertexProperties(f), (std::vector<std::string>{"x", "y", "z"}));
  EXPECT_THROW(upd::io::plyVertexProperties(dir.file("missing.ply")), std::runtime_error);
}

}  // namespace
