// The traversability grid as MRPT's occupancy grid: same window and cell size, non-traversable
// cells occupied at their position, unknown cells 0.5.
#include "maps/frames.h"
#include "upd/maps/grid_fusion.h"
#include "upd/mrpt_bridge/occupancy_grid.h"

#include <gtest/gtest.h>


using upd::maps::TraversabilityGrid;
using upd::test::kFreeX;
using upd::test::kFreeY;
using upd::test::kObsX;
using upd::test::kObsY;
using upd::test::twoCellGrid;

TEST(OccupancyGrid, NonTraversableCellsAreOccupiedAtTheirPosition) {
  const TraversabilityGrid g = twoCellGrid();
  const mrpt::maps::COccupancyGridMap2D occ = upd::mrpt_bridge::toOccupancyGrid(g);
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
