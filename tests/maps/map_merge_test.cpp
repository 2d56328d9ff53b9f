// Merging and cropping maps (map_merge.h): the cell rule, the covering window, pruned octree
// leaves merged voxel by voxel, and crops that keep exactly their region.
#include "upd/maps/map_merge.h"

#include <gtest/gtest.h>

#include <cmath>

namespace upd::maps {
namespace {

GridCell cell(float logodds, float zeta_min, float cost, std::uint32_t hits, float z) {
  GridCell c;
  c.logodds_nontrav = logodds;
  c.zeta_min = c.zeta_mean = zeta_min;
  c.cost_mean = cost;
  c.elevation_m = c.elevation_max_m = z;
  c.hits = c.zeta_count = c.cost_count = hits;
  c.last_seen_s = hits;
  return c;
}

TEST(MergeCells, AddsLogOddsTakesMinimaAndWeightsMeans) {
  const FusionParams f;
  const GridCell a = cell(0.85f, 0.6f, 0.2f, 10, 1.0f), b = cell(-0.4f, 0.9f, 0.8f, 30, 2.0f);
  const GridCell m = mergeCells(a, b, f);
  EXPECT_FLOAT_EQ(m.logodds_nontrav, 0.45f);
  EXPECT_FLOAT_EQ(m.zeta_min, 0.6f);
  EXPECT_FLOAT_EQ(m.cost_mean, (0.2f * 10 + 0.8f * 30) / 40);
  EXPECT_FLOAT_EQ(m.elevation_m, 1.75f);
  EXPECT_FLOAT_EQ(m.elevation_max_m, 2.0f);
  EXPECT_EQ(m.hits, 40u);
  EXPECT_EQ(m.last_seen_s, 30.0);
  // Clamped as the frame rule is; an unobserved cell adds nothing; the order does not matter.
  EXPECT_FLOAT_EQ(mergeCells(cell(3.0f, 0, 0, 1, 0), cell(3.0f, 0, 0, 1, 0), f).logodds_nontrav,
                  static_cast<float>(f.logodds_max));
  EXPECT_EQ(mergeCells(a, GridCell{}, f).hits, a.hits);
  EXPECT_EQ(mergeCells(GridCell{}, b, f).cost_mean, b.cost_mean);
  EXPECT_FLOAT_EQ(mergeCells(b, a, f).cost_mean, m.cost_mean);
}

GridParams fixed(double cx, double cy, double extent) {
  GridParams p;
  p.follow_robot = false;
  p.center_x_m = cx;
  p.center_y_m = cy;
  p.extent_m = extent;
  return p;
}

TEST(MergeGrid, TheCoveringWindowHoldsBothMaps) {
  TraversabilityGrid a(fixed(0, 0, 2)), b(fixed(5, -3, 2));
  *a.cellAt(0.55, -0.45) = cell(1, 0.5f, 0.5f, 3, 0);
  *b.cellAt(5.55, -3.45) = cell(-1, 0.9f, 0.1f, 4, 0);
  TraversabilityGrid u = windowCovering(a, b);
  EXPECT_LE(u.xMin(), a.xMin());
  EXPECT_GE(u.xMax(), b.xMax());
  EXPECT_EQ(mergeGridInto(u, a, {}), 0u);
  EXPECT_EQ(mergeGridInto(u, b, {}), 0u);
  EXPECT_EQ(u.cellAt(0.55, -0.45)->hits, 3u);
  EXPECT_EQ(u.cellAt(5.55, -3.45)->hits, 4u);
  EXPECT_EQ(computeStats(u).known, 2u);
  // A window too small for b: its cell is counted, not merged.
  EXPECT_EQ(mergeGridInto(a, b, {}), 1u);
  GridParams coarse = fixed(0, 0, 2);
  coarse.cell_size_m = 0.2;
  EXPECT_THROW(mergeGridInto(a, TraversabilityGrid(coarse), {}), std::invalid_argument);
}

TEST(CropGrid, KeepsTheCellsOfTheRegion) {
  TraversabilityGrid g(fixed(0, 0, 4));
  *g.cellAt(0.05, 0.05) = cell(1, 0.5f, 0.5f, 3, 0);
  *g.cellAt(1.05, 0.05) = cell(1, 0.5f, 0.5f, 3, 0);
  const TraversabilityGrid c = cropGrid(g, {-0.5, -0.3, 0.5, 0.2});
  EXPECT_DOUBLE_EQ(c.xMin(), -0.5);
  EXPECT_DOUBLE_EQ(c.yMin(), -0.3);
  EXPECT_EQ(computeStats(c).known, 1u);
  EXPECT_EQ(c.cellAt(0.05, 0.05)->hits, 3u);
  EXPECT_THROW(cropGrid(g, {1, 0, 0, 1}), std::invalid_argument);
}

TEST(MergeOctree, PrunedLeavesMergeVoxelByVoxel) {
  TraversabilityOcTree a(0.1), b(0.1);
  // b: a 2 x 2 x 2 block of equal occupied voxels, pruned into one leaf at depth 15.
  for (double x : {0.05, 0.15}) {
    for (double y : {0.05, 0.15}) {
      for (double z : {0.05, 0.15}) b.updateNode(x, y, z, 2.0f);
    }
  }
  b.prune();
  ASSERT_EQ(b.getNumLeafNodes(), 1u);
  a.updateNode(0.05, 0.05, 0.05, -1.0f);
  mergeOctreeInto(a, b, {});
  for (double x : {0.05, 0.15}) {
    const auto* n = a.search(x, 0.15, 0.05);
    ASSERT_NE(n, nullptr);
    EXPECT_FLOAT_EQ(n->getLogOdds(), 2.0f);
  }
  EXPECT_FLOAT_EQ(a.search(0.05, 0.05, 0.05)->getLogOdds(), 1.0f);
  cropOctree(a, {0.1, 0.0, 1.0, 1.0});
  EXPECT_EQ(a.search(0.05, 0.05, 0.05), nullptr);
  EXPECT_NE(a.search(0.15, 0.05, 0.05), nullptr);
}

}  // namespace
}  // namespace upd::maps
