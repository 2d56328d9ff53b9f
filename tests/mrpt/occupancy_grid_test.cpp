// The traversability grid as MRPT's occupancy grid: same window and cell size, non-traversable
// cells occupied at their position, unknown cells 0.5.
#include "maps/frames.h"
#include "upd/maps/grid_fusion.h"
#include "upd/mrpt/occupancy_grid.h"

#include <gtest/gtest.h>

using upd::Label;
using upd::maps::FusionParams;
using upd::maps::GridParams;
using upd::maps::TraversabilityGrid;
using upd::test::Frame;

namespace {

// An 8 m square window of 0.1 m cells centred at (1, -2), so x in [-3, 5) and y in [-6, 2),
// with an obstacle cell at (2.35, -1.25), a traversable cell at (0.55, -3.05), nothing else.
constexpr double kObsX = 2.35, kObsY = -1.25, kFreeX = 0.55, kFreeY = -3.05;

TraversabilityGrid makeGrid() {
  GridParams gp;
  gp.cell_size_m = 0.1;
  gp.extent_m = 8.0;
  gp.follow_robot = false;
  gp.center_x_m = 1.0;
  gp.center_y_m = -2.0;
  TraversabilityGrid g(gp);
  Frame f;
  f.fillCell(kObsX - 0.05, kObsY - 0.05, 0.1, 10, Label::NonTraversable);
  f.fillCell(kFreeX - 0.05, kFreeY - 0.05, 0.1, 10, Label::Traversable);
  for (int k = 0; k < 3; ++k) upd::maps::integrateScan(g, f.view(), {1, -2}, k, FusionParams{});
  return g;
}

}  // namespace

TEST(OccupancyGrid, NonTraversableCellsAreOccupiedAtTheirPosition) {
  const TraversabilityGrid g = makeGrid();
  const mrpt::maps::COccupancyGridMap2D occ = upd::mrptbridge::toOccupancyGrid(g);
  EXPECT_EQ(static_cast<int>(occ.getSizeX()), g.sizeX());
  EXPECT_EQ(static_cast<int>(occ.getSizeY()), g.sizeY());
  EXPECT_NEAR(occ.getResolution(), 0.1, 1e-6);
  EXPECT_NEAR(occ.getXMin(), g.xMin(), 1e-4);
  EXPECT_NEAR(occ.getYMin(), g.yMin(), 1e-4);
  EXPECT_GT(occ.getPos(kObsX, kObsY), 0.9f);
  EXPECT_LT(occ.getPos(kFreeX, kFreeY), 0.3f);
  EXPECT_NEAR(occ.getPos(kObsX + 0.1, kObsY), 0.5f, 0.01f);  // unknown neighbour
  EXPECT_NEAR(occ.getPos(-2.0, -5.0), 0.5f, 0.01f);
  // Exactly one occupied and one free cell.
  int occupied = 0, free = 0;
  for (unsigned cy = 0; cy < occ.getSizeY(); ++cy) {
    for (unsigned cx = 0; cx < occ.getSizeX(); ++cx) {
      const float p = occ.getCell(static_cast<int>(cx), static_cast<int>(cy));
      occupied += p > 0.65f ? 1 : 0;
      free += p < 0.35f ? 1 : 0;
    }
  }
  EXPECT_EQ(occupied, 1);
  EXPECT_EQ(free, 1);
}
