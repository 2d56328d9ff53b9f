// The ROS map_server writer and reader: the files' bytes (P5 header, trinary values, north up,
// the YAML keys), a round trip, the label of a world position, and the errors.
#include "upd/io/ros_map.h"

#include "temp_dir.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <string>

namespace core = upd::core;

namespace upd::io {
namespace {

RosMap sample() {
  RosMap m;
  m.resolution_m = 0.05;
  m.origin_xy = {-1.0, 2.0};
  m.width = 3;
  m.height = 2;
  // Bottom row (iy = 0) then the top row.
  m.labels = {core::Label::Traversable,    core::Label::NonTraversable, core::Label::Unknown,
              core::Label::NonTraversable, core::Label::Traversable,    core::Label::Traversable};
  return m;
}

TEST(RosMap, WritesTheMapServerFormat) {
  const test::TempDir dir;
  writeRosMap(sample(), dir.file("truth.yaml"));
  const std::string pgm = test::readFileBytes(dir.file("truth.pgm"));
  const std::string header = "P5\n3 2\n255\n";
  ASSERT_EQ(pgm.size(), header.size() + 6);
  EXPECT_EQ(pgm.substr(0, header.size()), header);
  // Row 0 of the image is the top (iy = 1).
  const std::string pixels = pgm.substr(header.size());
  EXPECT_EQ(static_cast<std::uint8_t>(pixels[0]), kRosOccupied);
  EXPECT_EQ(static_cast<std::uint8_t>(pixels[1]), kRosFree);
  EXPECT_EQ(static_cast<std::uint8_t>(pixels[3]), kRosFree);
  EXPECT_EQ(static_cast<std::uint8_t>(pixels[5]), kRosUnknown);
  EXPECT_EQ(test::readFileBytes(dir.file("truth.yaml")),
            "image: truth.pgm\nresolution: 0.05\norigin: [-1, 2, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n");
  EXPECT_EQ(dir.listing().size(), 2u);  // no temporary file left
}

TEST(RosMap, RoundTripAndLabelsOfWorldPositions) {
  const test::TempDir dir;
  const RosMap m = sample();
  writeRosMap(m, dir.file("m.yaml"));
  const RosMap r = readRosMap(dir.file("m.yaml"));
  EXPECT_EQ(r.width, 3);
  EXPECT_EQ(r.height, 2);
  EXPECT_DOUBLE_EQ(r.resolution_m, 0.05);
  EXPECT_TRUE(r.origin_xy.isApprox(m.origin_xy));
  EXPECT_EQ(r.labels, m.labels);
  EXPECT_EQ(r.labelAt(-0.97, 2.02), core::Label::Traversable);     // cell (0, 0)
  EXPECT_EQ(r.labelAt(-0.93, 2.02), core::Label::NonTraversable);  // cell (1, 0)
  EXPECT_EQ(r.labelAt(-0.88, 2.07), core::Label::Traversable);     // cell (2, 1)
  EXPECT_EQ(r.labelAt(-1.01, 2.02), core::Label::Unknown);         // outside
  EXPECT_EQ(r.labelAt(-0.97, 2.11), core::Label::Unknown);
  for (core::Label l : {core::Label::Traversable, core::Label::NonTraversable, core::Label::Unknown}) {
    EXPECT_EQ(labelOfRosPixel(rosPixelOf(l)), l);
  }
}

TEST(RosMap, ErrorsNameTheFile) {
  const test::TempDir dir;
  RosMap bad = sample();
  bad.labels.pop_back();
  EXPECT_THROW(writeRosMap(bad, dir.file("b.yaml")), std::invalid_argument);
  EXPECT_THROW(writeRosMap(sample(), dir.file("missing/m.yaml")), std::runtime_error);
  try {
    readRosMap(dir.file("none.yaml"));
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("none.yaml"), std::string::npos);
  }
  std::ofstream(dir.file("noimage.yaml")) << "resolution: 0.1\n";
  EXPECT_THROW(readRosMap(dir.file("noimage.yaml")), std::runtime_error);
  std::ofstream(dir.file("p2.yaml")) << "image: p2.pgm\n";
  std::ofstream(dir.file("p2.pgm")) << "P2\n1 1\n255\n0\n";
  EXPECT_THROW(readRosMap(dir.file("p2.yaml")), std::runtime_error);
}

// A damaged map_server pair is refused naming the file and the key or size that is wrong,
// before any allocation the header asks for.
TEST(RosMap, DamagedYamlOrPgmIsRefusedNamingWhatIsWrong) {
  const test::TempDir dir;
  writeRosMap(sample(), dir.file("m.yaml"));
  struct Case {
    std::string yaml, expected;
  };
  const std::string img = "image: m.pgm\n";
  for (const Case& c : {Case{img + "resolution: abc\norigin: [0, 0, 0]\n",
                             "resolution 'abc' is not a number > 0"},
                        Case{img + "resolution: 0\norigin: [0, 0, 0]\n", "resolution '0' is not"},
                        Case{img + "resolution: nan\norigin: [0, 0, 0]\n", "resolution 'nan'"},
                        Case{img + "resolution: 0.05 m\norigin: [0, 0, 0]\n", "resolution '0.05 m'"},
                        Case{img + "resolution: 0.05\norigin: [x, 0, 0]\n", "origin is not"},
                        Case{img + "resolution: 0.05\norigin: [inf, 0, 0]\n", "origin is not"},
                        Case{img + "origin: [0, 0, 0]\n", "no resolution key"},
                        Case{img + "resolution: 0.05\n", "no origin key"}}) {
    const std::string path = dir.file("bad.yaml");
    std::ofstream(path) << c.yaml;
    try {
      readRosMap(path);
      ADD_FAILURE() << c.yaml << ": read";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("ROS map " + path + ": " + c.expected),
                std::string::npos)
          << e.what();
    }
  }
  // A PGM whose header claims 100000 x 100000 pixels (10 GB) over 6 bytes of data.
  std::ofstream(dir.file("huge.yaml")) << "image: huge.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  std::ofstream(dir.file("huge.pgm"), std::ios::binary) << "P5\n100000 100000\n255\n" << std::string(6, '\xfe');
  try {
    readRosMap(dir.file("huge.yaml"));
    ADD_FAILURE() << "huge.pgm read";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("huge.pgm: truncated (100000 x 100000 pixels, 6 bytes"),
              std::string::npos)
        << e.what();
  }
}

// A world position far from the map (beyond any int cell index) is outside it, not converted.
TEST(RosMap, PositionFarOffTheMapIsUnknown) {
  const RosMap m = sample();
  EXPECT_EQ(m.labelAt(-0.975, 2.025), core::Label::Traversable);
  for (const double x : {1e12, -1e12, 1e300, std::nan("")}) {
    EXPECT_EQ(m.labelAt(x, 2.025), core::Label::Unknown) << x;
    EXPECT_EQ(m.labelAt(-0.975, x), core::Label::Unknown) << x;
  }
}

}  // namespace
}  // namespace upd::io
