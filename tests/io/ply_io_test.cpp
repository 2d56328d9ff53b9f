// PLY reader and writers: binary round trips, hand-made ascii and big-endian files with elements
// and list properties to skip, the scored PLY's exact header and body, and clean failures.
#include "io_test_util.h"
#include "upd/core/version.h"
#include "upd/io/cloud_io.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace core = upd::core;

namespace {

namespace fs = std::filesystem;
using upd::core::Label;
using upd::core::PointCloud;

/// A fresh directory per test, removed afterwards.
using upd::test::TempDir;

// The first comment of every PLY the project writes: the release that wrote it.
const std::string kMadeBy = std::string("comment UPD-Nav ") + upd::core::version();

void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

using upd::test::readBytes;

template <class T>
void appendBigEndian(std::string& out, T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (std::size_t i = sizeof(T); i > 0; --i) out.push_back(static_cast<char>(b[i - 1]));
}

template <class T>
void appendLittleEndian(std::string& out, T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (std::size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<char>(b[i]));
}

template <class T>
T loadLittleEndian(const std::string& bytes, std::size_t at) {
  T v;
  std::memcpy(&v, bytes.data() + at, sizeof(T));
  return v;
}

core::PointCloud randomCloud(std::size_t n, bool color, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> coord(-50.f, 50.f);
  std::uniform_int_distribution<int> byte(0, 255);
  core::PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    if (color) {
      c.push_back(coord(rng), coord(rng), coord(rng), static_cast<std::uint8_t>(byte(rng)),
                  static_cast<std::uint8_t>(byte(rng)), static_cast<std::uint8_t>(byte(rng)));
    } else {
      c.push_back(coord(rng), coord(rng), coord(rng));
    }
  }
  return c;
}

/// Header lines of a PLY up to and including end_header, and the offset of the body.
std::vector<std::string> headerLines(const std::string& bytes, std::size_t* body = nullptr) {
  std::vector<std::string> lines;
  std::size_t pos = 0;
  while (pos < bytes.size()) {
    const std::size_t nl = bytes.find('\n', pos);
    if (nl == std::string::npos) break;
    lines.push_back(bytes.substr(pos, nl - pos));
    pos = nl + 1;
    if (lines.back() == "end_header") break;
  }
  if (body) *body = pos;
  return lines;
}

void expectSameCloud(const core::PointCloud& a, const core::PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.hasColor(), b.hasColor());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.x[i], b.x[i]) << i;
    ASSERT_EQ(a.y[i], b.y[i]) << i;
    ASSERT_EQ(a.z[i], b.z[i]) << i;
    if (a.hasColor()) {
      ASSERT_EQ(a.r[i], b.r[i]) << i;
      ASSERT_EQ(a.g[i], b.g[i]) << i;
      ASSERT_EQ(a.b[i], b.b[i]) << i;
    }
  }
}

/// Expects fn to throw std::runtime_error whose message contains every one of parts.
template <class Fn>
void expectErrorContaining(Fn fn, const std::vector<std::string>& parts) {
  try {
    fn();
    ADD_FAILURE() << "no exception thrown";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    for (const auto& p : parts) EXPECT_NE(msg.find(p), std::string::npos) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << "message should be one line: " << msg;
  }
}

TEST(PlyIo, BinaryRoundTripWithoutColour) {
  TempDir dir;
  const core::PointCloud c = randomCloud(100000, false, 1);  // more than one writer/reader chunk
  const std::string f = dir.file("plain.ply");
  upd::io::writePly(f, c);
  const core::PointCloud back = upd::io::readPly(f);
  expectSameCloud(c, back);
  EXPECT_FALSE(back.isOrganized());
  EXPECT_EQ(back.width, c.size());
  EXPECT_EQ(back.height, 1u);
}

// The sensor origin orients the normals of vertical surfaces (towards the sensor): a PLY that
// dropped it left a generated scene's wall with normals of both signs once read back.
TEST(PlyIo, SensorOriginSurvivesTheRoundTrip) {
  TempDir dir;
  core::PointCloud c = randomCloud(50, false, 2);
  c.sensor_origin = Eigen::Vector3f(1.5f, -0.25f, 1e-7f);
  const std::string f = dir.file("origin.ply");
  upd::io::writePly(f, c);
  EXPECT_EQ(upd::io::readPly(f).sensor_origin, c.sensor_origin);
  c.sensor_origin.setZero();  // the default: no header line
  upd::io::writePly(f, c);
  EXPECT_EQ(readBytes(f).find("sensor_origin"), std::string::npos);
  EXPECT_EQ(upd::io::readPly(f).sensor_origin, Eigen::Vector3f::Zero());
  writeBytes(f, "ply\nformat ascii 1.0\ncomment sensor_origin 1 x 2\nelement vertex 0\n"
                "property float x\nproperty float y\nproperty float z\nend_header\n");
  expectErrorContaining([&] { upd::io::readPly(f); }, {f, "sensor_origin", "'x'"});
}

TEST(PlyIo, BinaryRoundTripWithColourAndLabels) {
  TempDir dir;
  const core::PointCloud c = randomCloud(777, true, 2);
  std::vector<core::Label> labels(c.size());
  for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = static_cast<core::Label>(i % 3);
  const std::string f = dir.file("labelled.PLY");  // upper-case extension dispatches too
  upd::io::writePly(f, c, &labels);

  const std::string bytes = readBytes(f);
  std::size_t body = 0;
  const auto h = headerLines(bytes, &body);
  const std::vector<std::string> expected = {
      "ply",           "format binary_little_endian 1.0", kMadeBy,
      "element vertex 777", "property float x",           "property float y",
      "property float z",   "property uchar label",       "property uchar red",
      "property uchar green", "property uchar blue",      "end_header"};
  EXPECT_EQ(h, expected);
  const std::size_t stride = 3 * 4 + 1 + 3;
  ASSERT_EQ(bytes.size(), body + c.size() * stride);
  for (std::size_t i = 0; i < c.size(); ++i) {
    EXPECT_EQ(static_cast<unsigned char>(bytes[body + i * stride + 12]), i % 3);
  }
  expectSameCloud(c, upd::io::readCloud(f));
}

TEST(PlyIo, NanPointsAreKeptUnlessDropped) {
  TempDir dir;
  core::PointCloud c;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  c.push_back(1, 2, 3);
  c.push_back(nan, nan, nan);
  c.push_back(4, 5, 6);
  const std::string kept = dir.file("kept.ply");
  upd::io::writePly(kept, c);
  const core::PointCloud a = upd::io::readPly(kept);
  ASSERT_EQ(a.size(), 3u);
  EXPECT_TRUE(std::isnan(a.x[1]));

  upd::io::PlyWriteOptions opt;
  opt.drop_non_finite_xyz = true;
  opt.comments = {"made by a test\nwith a newline"};
  const std::string dropped = dir.file("dropped.ply");
  upd::io::writePly(dropped, c, nullptr, opt);
  const core::PointCloud b = upd::io::readPly(dropped);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b.x[1], 4.f);
  const auto h = headerLines(readBytes(dropped));
  EXPECT_EQ(h[3], "comment made by a test with a newline");
}

TEST(PlyIo, WritePlyRejectsWrongLabelCount) {
  TempDir dir;
  const core::PointCloud c = randomCloud(5, false, 3);
  const std::vector<core::Label> labels(4, core::Label::Traversable);
  EXPECT_THROW(upd::io::writePly(dir.file("x.ply"), c, &labels), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir.file("x.ply")));
}

TEST(PlyIo, ReadsHandWrittenAsciiWithOtherElementsAndLists) {
  TempDir dir;
  const std::string f = dir.file("ascii.ply");
  writeBytes(f,
             "ply\r\n"  // CRLF line ends are accepted
             "format ascii 1.0\n"
             "comment hand written\n"
             "obj_info nothing\n"
             "element camera 1\n"
             "property float view_px\n"
             "property list uchar int junk\n"
             "element vertex 3\n"
             "property double x\n"
             "property float y\n"
             "property int extra\n"
             "property float z\n"
             "property uchar red\n"
             "property uchar green\n"
             "property uchar blue\n"
             "property list uchar float vlist\n"
             "element face 1\n"
             "property list uchar int vertex_indices\n"
             "end_header\n"
             "1.5 2 3 4\n"
             "0.25 -1e2 7 +3 10 20 30 2 0.5 0.25\n"
             "\n"
             "1 2 -8 3 0 0 0 0\n"
             "-0.5 0.125 9 1e-3 255 128 1 1 9\n"
             "3 0 1 2\n");
  const core::PointCloud c = upd::io::readCloud(f);
  ASSERT_EQ(c.size(), 3u);
  ASSERT_TRUE(c.hasColor());
  EXPECT_FLOAT_EQ(c.x[0], 0.25f);
  EXPECT_FLOAT_EQ(c.y[0], -100.f);
  EXPECT_FLOAT_EQ(c.z[0], 3.f);
  EXPECT_EQ(c.r[0], 10);
  EXPECT_EQ(c.g[0], 20);
  EXPECT_EQ(c.b[0], 30);
  EXPECT_FLOAT_EQ(c.x[1], 1.f);
  EXPECT_FLOAT_EQ(c.z[1], 3.f);
  EXPECT_FLOAT_EQ(c.x[2], -0.5f);
  EXPECT_FLOAT_EQ(c.y[2], 0.125f);
  EXPECT_FLOAT_EQ(c.z[2], 0.001f);
  EXPECT_EQ(c.r[2], 255);
  EXPECT_EQ(c.g[2], 128);
  EXPECT_EQ(c.b[2], 1);
}

TEST(PlyIo, AsciiErrorsNameTheLine) {
  TempDir dir;
  const std::string f = dir.file("bad_ascii.ply");
  writeBytes(f,
             "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
             "property float z\nend_header\n1 2 3\n4 five 6\n");
  expectErrorContaining([&] { upd::io::readPly(f); }, {f, "line 9", "five"});

  const std::string g = dir.file("short_ascii.ply");
  writeBytes(g,
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
             "property float z\nend_header\n1 2 3\n4 5 6\n");
  expectErrorContaining([&] { upd::io::readPly(g); }, {g, "truncated"});

  const std::string h = dir.file("extra_ascii.ply");
  writeBytes(h,
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
             "property float z\nend_header\n1 2 3 4\n");
  expectErrorContaining([&] { upd::io::readPly(h); }, {h, "line 8"});
}

/// A big-endian file: an element with lists before the vertices, a double and a ushort among
/// the vertex properties, faces after.
std::string bigEndianPly() {
  std::string s =
      "ply\n"
      "format binary_big_endian 1.0\n"
      "element junk 2\n"
      "property short a\n"
      "property list uchar int items\n"
      "element vertex 2\n"
      "property float x\n"
      "property double y\n"
      "property ushort intensity\n"
      "property float z\n"
      "property uchar red\n"
      "property uchar green\n"
      "property uchar blue\n"
      "element face 1\n"
      "property list uchar int vertex_indices\n"
      "end_header\n";
  // junk 0: a = 7, items = {1, 2, 3}; junk 1: a = -1, items = {}
  appendBigEndian<std::int16_t>(s, 7);
  s.push_back(3);
  for (std::int32_t v : {1, 2, 3}) appendBigEndian(s, v);
  appendBigEndian<std::int16_t>(s, -1);
  s.push_back(0);
  // vertices
  appendBigEndian(s, 1.5f);
  appendBigEndian(s, -2.25);
  appendBigEndian<std::uint16_t>(s, 4000);
  appendBigEndian(s, 1e6f);
  s += std::string{'\x01', '\x02', '\x03'};
  appendBigEndian(s, -0.0625f);
  appendBigEndian(s, 123456.5);
  appendBigEndian<std::uint16_t>(s, 1);
  appendBigEndian(s, 3.f);
  s += std::string{'\xff', '\x00', '\x80'};
  // one face
  s.push_back(2);
  appendBigEndian<std::int32_t>(s, 0);
  appendBigEndian<std::int32_t>(s, 1);
  return s;
}

TEST(PlyIo, ReadsHandWrittenBigEndian) {
  TempDir dir;
  const std::string f = dir.file("be.ply");
  writeBytes(f, bigEndianPly());
  const core::PointCloud c = upd::io::readPly(f);
  ASSERT_EQ(c.size(), 2u);
  ASSERT_TRUE(c.hasColor());
  EXPECT_EQ(c.x[0], 1.5f);
  EXPECT_EQ(c.y[0], -2.25f);
  EXPECT_EQ(c.z[0], 1e6f);
  EXPECT_EQ(c.r[0], 1);
  EXPECT_EQ(c.g[0], 2);
  EXPECT_EQ(c.b[0], 3);
  EXPECT_EQ(c.x[1], -0.0625f);
  EXPECT_EQ(c.y[1], 123456.5f);
  EXPECT_EQ(c.z[1], 3.f);
  EXPECT_EQ(c.r[1], 255);
  EXPECT_EQ(c.g[1], 0);
  EXPECT_EQ(c.b[1], 128);
}

TEST(PlyIo, TruncatedBigEndianFailsCleanly) {
  TempDir dir;
  const std::string full = bigEndianPly();
  // Cut inside the junk element, inside the vertices, and just before the last vertex byte.
  const std::size_t header = full.find("end_header\n") + 11;
  for (const std::size_t keep : {header + 5, header + 30, header + 18 + 2 * 21 - 1}) {
    const std::string f = dir.file("be_cut_" + std::to_string(keep) + ".ply");
    writeBytes(f, full.substr(0, keep));
    expectErrorContaining([&] { upd::io::readPly(f); }, {f, "truncated"});
  }
}

TEST(PlyIo, VertexElementWithListPropertyLittleEndian) {
  TempDir dir;
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property list uchar ushort neighbours\nproperty float y\nproperty float z\nend_header\n";
  for (int i = 0; i < 3; ++i) {
    appendLittleEndian(s, static_cast<float>(i));
    s.push_back(static_cast<char>(i));  // i list items
    for (int k = 0; k < i; ++k) appendLittleEndian<std::uint16_t>(s, 9);
    appendLittleEndian(s, static_cast<float>(10 + i));
    appendLittleEndian(s, static_cast<float>(20 + i));
  }
  const std::string f = dir.file("vlist.ply");
  writeBytes(f, s);
  const core::PointCloud c = upd::io::readPly(f);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_FALSE(c.hasColor());
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(c.x[i], static_cast<float>(i));
    EXPECT_EQ(c.y[i], static_cast<float>(10 + i));
    EXPECT_EQ(c.z[i], static_cast<float>(20 + i));
  }
  writeBytes(f, s.substr(0, s.size() - 3));
  expectErrorContaining([&] { upd::io::readPly(f); }, {f, "truncated"});
}

TEST(PlyIo, TruncatedBinaryCopyFailsWithFileName) {
  TempDir dir;
  const std::string f = dir.file("whole.ply");
  upd::io::writePly(f, randomCloud(1000, true, 4));
  const std::string bytes = readBytes(f);
  const std::string cut = dir.file("cut.ply");
  writeBytes(cut, bytes.substr(0, bytes.size() / 2));
  expectErrorContaining([&] { upd::io::readCloud(cut); }, {cut, "truncated", "1000 vertices"});
  const std::string header_only = dir.file("header_cut.ply");
  writeBytes(header_only, bytes.substr(0, 40));
  expectErrorContaining([&] { upd::io::readCloud(header_only); }, {header_only, "end_header"});
}

TEST(PlyIo, MalformedHeadersFailCleanly) {
  TempDir dir;
  const struct {
    const char* text;
    const char* expect;
  } cases[] = {
      {"not a ply\n", "magic"},
      {"ply\nformat ascii 2.0\nend_header\n", "version"},
      {"ply\nformat binary_middle_endian 1.0\nend_header\n", "format"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n", "float128"},
      {"ply\nformat ascii 1.0\nelement vertex -4\nend_header\n", "count"},
      {"ply\nformat ascii 1.0\nelement face 0\nend_header\n", "no vertex element"},
      {"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nend_header\n", "x/y/z"},
      {"ply\nelement vertex 0\nend_header\n", "format"},
  };
  int k = 0;
  for (const auto& c : cases) {
    const std::string f = dir.file("bad" + std::to_string(k++) + ".ply");
    writeBytes(f, c.text);
    expectErrorContaining([&] { upd::io::readPly(f); }, {f, c.expect});
  }
}

TEST(PlyIo, EmptyCloudRoundTrips) {
  TempDir dir;
  const std::string f = dir.file("empty.ply");
  upd::io::writePly(f, core::PointCloud{});
  EXPECT_TRUE(upd::io::readPly(f).empty());
}

TEST(ScoredPly, HeaderListsExactlyThePropertiesInOrder) {
  TempDir dir;
  const core::PointCloud c = randomCloud(4, true, 5);
  const std::vector<float> nx = {0, 0, 0, 0}, ny = {0, 0, 0, 0}, nz = {1, 1, 1, 1};
  const std::vector<float> rx = {0.1f, 0.2f, 0.3f, 0.4f}, ry = {0, 0, 0, 0},
                           rz = {3, 3, 3, std::numeric_limits<float>::quiet_NaN()};
  const std::vector<float> zeta = {1.f, 0.99f, 0.8f, std::numeric_limits<float>::quiet_NaN()};
  const std::vector<core::Label> label = {core::Label::Traversable, core::Label::Traversable, core::Label::NonTraversable,
                                    core::Label::Unknown};
  const std::vector<float> cost = {0.f, 0.5f, 1.f, std::numeric_limits<float>::quiet_NaN()};
  upd::io::ScoredPoints p;
  p.x = c.x;
  p.y = c.y;
  p.z = c.z;
  p.nx = nx;
  p.ny = ny;
  p.nz = nz;
  p.rx = rx;
  p.ry = ry;
  p.rz = rz;
  p.zeta = zeta;
  p.label = label;
  p.cost = cost;
  p.r = c.r;
  p.g = c.g;
  p.b = c.b;
  const std::string f = dir.file("scored.ply");
  upd::io::writeScoredPly(f, p);

  const std::string bytes = readBytes(f);
  std::size_t body = 0;
  const auto h = headerLines(bytes, &body);
  const std::vector<std::string> expected = {
      "ply",
      "format binary_little_endian 1.0",
      kMadeBy,
      "element vertex 4",
      "property float x",
      "property float y",
      "property float z",
      "property float nx",
      "property float ny",
      "property float nz",
      "property float scalar_rx",
      "property float scalar_ry",
      "property float scalar_rz",
      "property float scalar_zeta",
      "property uchar scalar_label",
      "property float scalar_cost",
      "property float quality",
      "property uchar red",
      "property uchar green",
      "property uchar blue",
      "end_header"};
  EXPECT_EQ(h, expected);
  const auto& names = upd::io::scoredPlyProperties();
  ASSERT_EQ(names.size(), 13u);
  for (std::size_t i = 0; i < names.size(); ++i) {
    EXPECT_NE(h[4 + i].find(" " + names[i]), std::string::npos);
  }

  const std::size_t stride = 10 * 4 + 1 + 4 + 4 + 3;
  ASSERT_EQ(bytes.size(), body + 4 * stride);
  for (std::size_t i = 0; i < 4; ++i) {
    const std::size_t at = body + i * stride;
    EXPECT_EQ(loadLittleEndian<float>(bytes, at + 0), c.x[i]);
    EXPECT_EQ(loadLittleEndian<float>(bytes, at + 8), c.z[i]);
    EXPECT_EQ(loadLittleEndian<float>(bytes, at + 20), nz[i]);
    EXPECT_EQ(loadLittleEndian<float>(bytes, at + 24), rx[i]);
    const float z = loadLittleEndian<float>(bytes, at + 36);
    if (std::isnan(zeta[i])) {
      EXPECT_TRUE(std::isnan(z));
    } else {
      EXPECT_EQ(z, zeta[i]);
    }
    EXPECT_EQ(static_cast<unsigned char>(bytes[at + 40]), static_cast<unsigned>(label[i]));
    const float k = loadLittleEndian<float>(bytes, at + 41);
    if (std::isnan(cost[i])) {
      EXPECT_TRUE(std::isnan(k));
    } else {
      EXPECT_EQ(k, cost[i]);
    }
    const float quality = loadLittleEndian<float>(bytes, at + 45);  // zeta again, for MeshLab
    EXPECT_TRUE(quality == zeta[i] || (std::isnan(quality) && std::isnan(zeta[i])));
    EXPECT_EQ(static_cast<unsigned char>(bytes[at + 49]), c.r[i]);
    EXPECT_EQ(static_cast<unsigned char>(bytes[at + 51]), c.b[i]);
  }
  // The scored file is still a cloud our reader (and any PLY reader) opens.
  expectSameCloud(c, upd::io::readPly(f));
}

TEST(ScoredPly, AbsentViewsAreNanAndUnknownAndNoColour) {
  TempDir dir;
  const core::PointCloud c = randomCloud(3, false, 6);
  upd::io::ScoredPoints p;
  p.x = c.x;
  p.y = c.y;
  p.z = c.z;
  const std::string f = dir.file("bare.ply");
  upd::io::writeScoredPly(f, p);
  const std::string bytes = readBytes(f);
  std::size_t body = 0;
  const auto h = headerLines(bytes, &body);
  ASSERT_EQ(h.size(), 4u + 13u + 1u);
  EXPECT_EQ(h[15], "property float scalar_cost");
  const std::size_t stride = 49;
  ASSERT_EQ(bytes.size(), body + 3 * stride);
  EXPECT_TRUE(std::isnan(loadLittleEndian<float>(bytes, body + 12)));  // nx
  EXPECT_TRUE(std::isnan(loadLittleEndian<float>(bytes, body + 36)));  // zeta
  EXPECT_EQ(static_cast<unsigned char>(bytes[body + 40]), static_cast<unsigned>(core::Label::Unknown));
}

// An organized 3 x 2 frame with two invalid pixels (NaN, as a depth image gives them).
upd::core::PipelineResult organizedResultWithHoles() {
  upd::core::PipelineResult r;
  r.cloud = randomCloud(6, false, 9);
  r.cloud.width = 3;
  r.cloud.height = 2;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  r.cloud.x[1] = r.cloud.y[1] = r.cloud.z[1] = nan;
  r.cloud.z[4] = std::numeric_limits<float>::infinity();
  r.upd.zeta = {1.f, nan, 0.9f, 0.8f, nan, 0.7f};
  r.classes.label.assign(6, core::Label::Traversable);
  r.classes.cost.assign(6, 0.25f);
  return r;
}

TEST(ScoredPly, InvalidPointsAreLeftOutByDefault) {
  TempDir dir;
  const upd::core::PipelineResult r = organizedResultWithHoles();
  const std::string f = dir.file("valid.ply");
  upd::io::writeScoredPly(f, r);
  const std::string bytes = readBytes(f);
  std::size_t body = 0;
  const auto h = headerLines(bytes, &body);
  EXPECT_EQ(h[3], "element vertex 4");
  ASSERT_EQ(bytes.size(), body + 4 * 49);
  const std::vector<std::size_t> kept = {0, 2, 3, 5};
  for (std::size_t v = 0; v < kept.size(); ++v) {
    const std::size_t at = body + v * 49;
    EXPECT_EQ(loadLittleEndian<float>(bytes, at), r.cloud.x[kept[v]]);
    EXPECT_EQ(loadLittleEndian<float>(bytes, at + 8), r.cloud.z[kept[v]]);
    EXPECT_EQ(loadLittleEndian<float>(bytes, at + 36), r.upd.zeta[kept[v]]);  // scalar_zeta
  }
  const core::PointCloud back = upd::io::readPly(f);
  ASSERT_EQ(back.size(), 4u);
  for (std::size_t i = 0; i < back.size(); ++i) {
    EXPECT_TRUE(std::isfinite(back.x[i]) && std::isfinite(back.y[i]) && std::isfinite(back.z[i]));
  }
}

TEST(ScoredPly, OrganizedKeepsEveryPixelWithWidthAndHeight) {
  TempDir dir;
  const upd::core::PipelineResult r = organizedResultWithHoles();
  const std::string f = dir.file("organized.ply");
  upd::io::ScoredPlyOptions options;
  options.organized = true;
  upd::io::writeScoredPly(f, r, options);
  const std::string bytes = readBytes(f);
  std::size_t body = 0;
  const auto h = headerLines(bytes, &body);
  EXPECT_EQ(h[2], kMadeBy);
  EXPECT_EQ(h[3], "comment width 3");
  EXPECT_EQ(h[4], "comment height 2");
  EXPECT_EQ(h[5], "element vertex 6");
  ASSERT_EQ(bytes.size(), body + 6 * 49);
  EXPECT_TRUE(std::isnan(loadLittleEndian<float>(bytes, body + 49)));  // pixel 1 is NaN
  EXPECT_EQ(upd::io::readPly(f).size(), 6u);

  upd::io::ScoredPoints p = upd::io::scoredPointsOf(r);
  EXPECT_EQ(p.width, 3u);
  EXPECT_EQ(p.height, 2u);
  p.width = 4;  // 4 x 2 != 6 points
  EXPECT_THROW(upd::io::writeScoredPly(dir.file("bad.ply"), p, options), std::invalid_argument);
}

TEST(ScoredPly, InconsistentSizesAreRejectedNamingTheField) {
  TempDir dir;
  const core::PointCloud c = randomCloud(3, true, 7);
  const std::vector<float> zeta(2, 1.f);
  upd::io::ScoredPoints p;
  p.x = c.x;
  p.y = c.y;
  p.z = c.z;
  p.zeta = zeta;
  try {
    upd::io::writeScoredPly(dir.file("s.ply"), p);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("zeta"), std::string::npos) << e.what();
  }
  p.zeta = {};
  p.r = c.r;  // g, b absent
  EXPECT_THROW(upd::io::writeScoredPly(dir.file("s.ply"), p), std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir.file("s.ply")));
}

TEST(ScoredPly, FromPipelineResult) {
  TempDir dir;
  upd::core::PipelineResult r;
  r.cloud = randomCloud(5, false, 8);
  r.normals.nx.assign(5, 0.f);
  r.normals.ny.assign(5, 0.f);
  r.normals.nz.assign(5, 1.f);
  r.upd.rx.assign(5, 0.f);
  r.upd.ry.assign(5, 0.f);
  r.upd.rz.assign(5, 5.f);
  r.upd.zeta.assign(5, 1.f);
  r.classes.label.assign(5, core::Label::NonTraversable);
  r.classes.cost.assign(5, 1.f);
  const std::string f = dir.file("result.ply");
  upd::io::writeScoredPly(f, r);
  const std::string bytes = readBytes(f);
  std::size_t body = 0;
  const auto h = headerLines(bytes, &body);
  EXPECT_EQ(h[3], "element vertex 5");
  ASSERT_EQ(bytes.size(), body + 5 * 49);
  EXPECT_EQ(loadLittleEndian<float>(bytes, body + 32), 5.f);  // rz
  EXPECT_EQ(static_cast<unsigned char>(bytes[body + 40]),
            static_cast<unsigned>(core::Label::NonTraversable));
  expectSameCloud(r.cloud, upd::io::readPly(f));
}

}  // namespace
