// The ROS map_server writer and reader: the files' bytes (P5 header, trinary values, north up,
// the YAML keys), a round trip, the label of a world position, and the errors.
#include "upd/io/ros_map.h"

#include "temp_dir.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace upd::io
