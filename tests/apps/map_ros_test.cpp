// The ROS maps as a ROS/MRPT user opens them: map.yaml (trinary) and map_cost.yaml (graded,
// mode scale) converted by MRPT's ros-map-yaml2mrpt (mrpt-apps) into an MRPT occupancy grid,
// whose cells must say what our grid says, where our grid says it.
#include "run_upd.h"
#include "temp_dir.h"
#include "upd/io/ros_map.h"
#include "upd/maps/fusion.h"
#include "upd/maps/grid_export.h"

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/maps/COccupancyGridMap2D.h>
#include <mrpt/serialization/CArchive.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace upd {
namespace {

// 0.2 m cells over [3, 7) x [-2, 2): an obstacle at (6.1, 1.3), a doubtful cell (p 0.55) at
// (3.3, -1.9), ground at (4.5, 0.1); the rest unknown.
maps::TraversabilityGrid sampleGrid() {
  maps::GridParams p;
  p.cell_size_m = 0.2;
  p.extent_m = 4.0;
  p.follow_robot = false;
  p.center_x_m = 5.0;
  p.center_y_m = 0.0;
  maps::TraversabilityGrid g(p);
  auto set = [&](double x, double y, float logodds) {
    maps::GridCell& c = *g.cellAt(x, y);
    c.logodds_nontrav = logodds;
    c.hits = 10;
  };
  set(6.1, 1.3, 3.0f);                       // p 0.953
  set(3.3, -1.9, std::log(0.55f / 0.45f));   // p 0.55
  set(4.5, 0.1, -2.0f);                      // p 0.119
  return g;
}

// ros-map-yaml2mrpt's output for yaml, read back as MRPT's grid.
mrpt::maps::COccupancyGridMap2D convertWithMrpt(const test::TempDir& dir, const std::string& yaml) {
  const test::CmdResult r = test::runCommand("ros-map-yaml2mrpt -q -w -i '" + dir.file(yaml) +
                                             "' -d '" + dir.path().string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const std::string stem = yaml.substr(0, yaml.size() - 5);
  mrpt::maps::COccupancyGridMap2D grid;
  mrpt::io::CFileGZInputStream in(dir.file(stem + ".gridmap.gz"));
  mrpt::serialization::archiveFrom(in) >> grid;
  return grid;
}

TEST(RosMapsInMrpt, TrinaryAndGradedMapsOpenWithRosMapYaml2mrpt) {
  if (std::system("command -v ros-map-yaml2mrpt >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "ros-map-yaml2mrpt not found (apt-get install mrpt-apps)";
  }
  const test::TempDir dir;
  const maps::TraversabilityGrid g = sampleGrid();
  maps::writeRosMap(g, dir.file("map"));
  maps::writeRosCostMap(g, dir.file("map_cost"));
  std::ifstream yaml(dir.file("map_cost.yaml"));
  std::stringstream text;
  text << yaml.rdbuf();
  EXPECT_NE(text.str().find("mode: scale\n"), std::string::npos) << text.str();

  const auto trinary = convertWithMrpt(dir, "map.yaml");
  const auto graded = convertWithMrpt(dir, "map_cost.yaml");
  for (const auto* m : {&trinary, &graded}) {
    EXPECT_NEAR(m->getXMin(), 3.0, 1e-6);
    EXPECT_NEAR(m->getYMin(), -2.0, 1e-6);
    EXPECT_NEAR(m->getResolution(), 0.2, 1e-6);
    EXPECT_EQ(m->getSizeX(), 20u);
    EXPECT_EQ(m->getSizeY(), 20u);
  }
  // MRPT's cell value is the probability of being FREE (white = free, as in the image).
  auto occupied = [](const mrpt::maps::COccupancyGridMap2D& m, double x, double y) {
    return 1.0 - m.getPos(static_cast<float>(x), static_cast<float>(y));
  };
  EXPECT_GT(occupied(trinary, 6.1, 1.3), 0.9);
  EXPECT_LT(occupied(trinary, 4.5, 0.1), 0.1);
  EXPECT_NEAR(occupied(trinary, 5.0, 0.0), 0.5, 0.01);  // unknown (grey 205 in trinary mode)
  // The graded map keeps each cell's probability (MRPT quantizes it to about 1 %).
  EXPECT_NEAR(occupied(graded, 6.1, 1.3), maps::probabilityFromLogOdds(3.0f), 0.02);
  EXPECT_NEAR(occupied(graded, 3.3, -1.9), 0.55, 0.02);
  EXPECT_NEAR(occupied(graded, 4.5, 0.1), maps::probabilityFromLogOdds(-2.0f), 0.02);
  EXPECT_NEAR(occupied(graded, 5.0, 0.0), 0.5, 0.02);  // unknown: the prior
}

TEST(RosMapsInMrpt, ScaleGreyLevels) {
  EXPECT_EQ(io::rosScalePixelOf(0.f), 255);
  EXPECT_EQ(io::rosScalePixelOf(1.f), 0);
  EXPECT_EQ(io::rosScalePixelOf(0.5f), 128);
  EXPECT_EQ(io::rosScalePixelOf(std::nanf("")), 128);
  EXPECT_EQ(io::rosScalePixelOf(2.f), 0);  // clamped
}

}  // namespace
}  // namespace upd
