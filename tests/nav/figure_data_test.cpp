// The scored PLY as `upd render` and `upd view` read it (io::readScoredPly): any PLY scalar type
// per property (a file re-saved by another tool), labels and colours converted only where the
// value is one, and a header that declares more vertices than the file holds refused before
// anything is allocated.
#include "temp_dir.h"
#include "upd/nav/figure.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace upd::nav {
namespace {

using core::Label;

// A binary little-endian scored PLY: coordinates in double, the rest in float (as a tool that
// re-saves scalar fields as floats writes it), colours as float 0..1.
struct Vertex {
  double x, y, z;
  float nx, ny, nz, zeta, label, cost, r, g, b;
};

void writePly(const std::string& path, const std::vector<Vertex>& vs, const std::string& count) {
  std::ofstream out(path, std::ios::binary);
  out << "ply\nformat binary_little_endian 1.0\nelement vertex " << count << "\n"
      << "property double x\nproperty double y\nproperty double z\n"
      << "property float nx\nproperty float ny\nproperty float nz\n"
      << "property float scalar_zeta\nproperty float scalar_label\nproperty float scalar_cost\n"
      << "property float red\nproperty float green\nproperty float blue\nend_header\n";
  for (const Vertex& v : vs) {
    const double xyz[3] = {v.x, v.y, v.z};
    const float rest[9] = {v.nx, v.ny, v.nz, v.zeta, v.label, v.cost, v.r, v.g, v.b};
    out.write(reinterpret_cast<const char*>(xyz), sizeof(xyz));
    out.write(reinterpret_cast<const char*>(rest), sizeof(rest));
  }
}

TEST(ScoredPly, AnyScalarTypeIsReadAndOnlyRealLabelsAndColoursConvert) {
  const test::TempDir dir("scored_ply");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::string path = dir.file("resaved.ply");
  writePly(path,
           {{1.5, -2.25, 0.125, 0.f, 0.f, 1.f, 0.99f, 0.f, 0.1f, 1.f, 0.5f, 0.f},
            {2.0, 0.0, 0.0, 0.f, 0.f, 1.f, 0.71f, 1.f, 0.9f, 2.f, -1.f, nan},
            {3.0, 0.0, 0.0, 0.f, 0.f, 1.f, 0.8f, -5.f, 0.5f, 0.f, 0.f, 0.f},
            {4.0, 0.0, 0.0, 0.f, 0.f, 1.f, 0.8f, nan, 0.5f, 0.f, 0.f, 0.f},
            {5.0, 0.0, 0.0, 0.f, 0.f, 1.f, 0.8f, 0.5f, 0.5f, 0.f, 0.f, 0.f}},
           "5");
  const ScoredCloud c = loadScoredCloud(path);
  ASSERT_EQ(c.size(), 5u);
  EXPECT_EQ(c.points[0], Eigen::Vector3f(1.5f, -2.25f, 0.125f));
  EXPECT_FLOAT_EQ(c.zeta[1], 0.71f);
  EXPECT_FLOAT_EQ(c.cost[1], 0.9f);
  EXPECT_EQ(c.label[0], Label::Traversable);
  EXPECT_EQ(c.label[1], Label::NonTraversable);
  for (int i : {2, 3, 4}) EXPECT_EQ(c.label[i], Label::Unknown) << "vertex " << i;
  ASSERT_EQ(c.rgb.size(), 5u);
  EXPECT_EQ(c.rgb[0], (std::array<std::uint8_t, 3>{255, 128, 0}));
  EXPECT_EQ(c.rgb[1], (std::array<std::uint8_t, 3>{255, 0, 0}));  // 2 -> 255, -1 -> 0, NaN -> 0
}

// 2^61 vertices of 60 bytes: the product wraps to a few bytes, and the rows were read past them.
TEST(ScoredPly, MoreVerticesThanTheFileHoldsIsRefusedNamingIt) {
  const test::TempDir dir("scored_ply");
  const Vertex v{1.0, 0.0, 0.0, 0.f, 0.f, 1.f, 1.f, 0.f, 0.f, 0.f, 0.f, 0.f};
  for (const char* count : {"2305843009213693952", "1000000000", "3"}) {
    const std::string path = dir.file(std::string("v") + count + ".ply");
    writePly(path, {v, v}, count);
    try {
      loadScoredCloud(path);
      ADD_FAILURE() << count << " vertices: read";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      const std::string declared = "': truncated PLY: the header declares " + std::string(count);
      EXPECT_NE(what.find("'" + path + declared + " vertices"), std::string::npos)
          << what;
      EXPECT_NE(what.find("only 120 bytes of data follow"), std::string::npos) << what;
    }
  }
  const std::string whole = dir.file("whole.ply");
  writePly(whole, {v, v}, "2");
  EXPECT_EQ(loadScoredCloud(whole).size(), 2u);
}

}  // namespace
}  // namespace upd::nav
