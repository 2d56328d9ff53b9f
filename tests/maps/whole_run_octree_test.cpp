// The octree's whole-run memory: subtrees that leave the update box are kept in compressed tiles
// and come back unchanged; the whole run equals one tree with a fixed box big enough for every
// frame; the kept bytes stay within the stated cost per leaf and tile.
#include "maps/frames.h"
#include "upd/maps/traversability_octree.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <random>
#include <tuple>

namespace core = upd::core;

using upd::maps::FusionParams;
using upd::maps::OctreeParams;
using upd::maps::TraversabilityOcTree;
using upd::test::Frame;

namespace {

using LeafId = std::tuple<int, int, int, unsigned>;  // key x, y, z, depth
using LeafData = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t, int>;

std::uint32_t bits(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

// Every leaf whose centre lies within |x|, |y| <= half_m of (cx, cy) (all of them for half_m < 0).
std::map<LeafId, LeafData> leaves(const TraversabilityOcTree& t, double cx = 0, double cy = 0,
                                  double half_m = -1) {
  std::map<LeafId, LeafData> out;
  for (auto it = t.begin_leafs(), end = t.end_leafs(); it != end; ++it) {
    if (half_m >= 0 && (std::abs(it.getX() - cx) > half_m || std::abs(it.getY() - cy) > half_m)) {
      continue;
    }
    const auto k = it.getKey();
    out[{k[0], k[1], k[2], it.getDepth()}] = {
        bits(it->getLogOdds()), bits(it->getTraversabilityLogOdds()), bits(it->getZetaMin()),
        bits(it->getCostMean()), it->getObservations()};
  }
  return out;
}

// n points on the ground within radius_m of (x, y), a few of them on rocks.
Frame groundFrame(std::mt19937& rng, double x, double y, double radius_m, int n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
  Frame f;
  while (static_cast<int>(f.x.size()) < n) {
    const double dx = radius_m * u(rng), dy = radius_m * u(rng);
    if (dx * dx + dy * dy > radius_m * radius_m) continue;
    const bool rock = unit(rng) < 0.15;
    f.add(static_cast<float>(x + dx), static_cast<float>(y + dy),
          static_cast<float>(rock ? 0.3 * unit(rng) : 0.02),
          rock ? core::Label::NonTraversable : core::Label::Traversable,
          static_cast<float>(rock ? 0.8 : 0.99), 0.f, static_cast<float>(unit(rng)));
  }
  return f;
}

OctreeParams rollingBox(int tile_voxels) {
  OctreeParams p;
  p.resolution_m = 0.1;
  p.max_range_m = 6.0;
  p.extent_m = 8.0;
  p.height_m = 4.0;
  p.center_z_m = 0.5;
  p.tile_voxels = tile_voxels;
  return p;
}

void expectWithinStatedCost(const TraversabilityOcTree& t) {
  // 25 bytes a leaf before compression, zlib's bound and 96 bytes of bookkeeping per tile.
  EXPECT_LE(t.keptTileBytes(), 26 * t.keptLeaves() + 128 * t.keptTiles());
}

}  // namespace

TEST(WholeRunOctree, SensorGoingOutAndComingBackGetsItsVoxelsBack) {
  const OctreeParams p = rollingBox(32);
  TraversabilityOcTree tree(p);
  std::mt19937 rng(4);
  for (int k = 0; k < 5; ++k) {
    upd::maps::insertScan(tree, groundFrame(rng, 0.0, 0.0, 1.4, 300).view(), {0, 0, 0.5}, p,
                          FusionParams{});
  }
  const auto before = leaves(tree, 0, 0, 1.5);
  ASSERT_GT(before.size(), 200u);
  const std::size_t nodes_near_start = tree.size();
  for (double x = 1.0; x <= 40.0; x += 1.0) {
    upd::maps::insertScan(tree, groundFrame(rng, x, 10.0, 1.4, 200).view(), {x, 10.0, 0.5}, p,
                          FusionParams{});
    EXPECT_LT(tree.size(), 4 * nodes_near_start) << "x " << x;
    expectWithinStatedCost(tree);
  }
  EXPECT_GT(tree.keptTiles(), 5u);
  EXPECT_EQ(tree.search(0.05, 0.05, 0.05), nullptr);  // left the box
  const Frame nothing;
  upd::maps::insertScan(tree, nothing.view(), {0, 0, 0.5}, p, FusionParams{});  // back
  EXPECT_EQ(leaves(tree, 0, 0, 1.5), before);
  // The whole run holds the start and the far end.
  const auto whole = tree.wholeRun();
  EXPECT_EQ(leaves(*whole, 0, 0, 1.5), before);
  EXPECT_GT(leaves(*whole, 40.0, 10.0, 1.0).size(), 100u);
}

// Property: over random paths (fixed seeds) the whole run of the moving box equals a tree with
// one fixed box holding every frame, leaf for leaf, when every ray stays inside the moving box.
TEST(WholeRunOctree, EqualsOneFixedBoxTreeFedTheSameFrames) {
  for (const int tile_voxels : {16, 64}) {
    SCOPED_TRACE(tile_voxels);
    const OctreeParams p = rollingBox(tile_voxels);
    OctreeParams fixed_p = p;
    fixed_p.follow_robot = false;
    fixed_p.extent_m = 80.0;
    TraversabilityOcTree roll(p), fixed(fixed_p);
    std::mt19937 rng(static_cast<unsigned>(tile_voxels));
    std::uniform_real_distribution<double> turn(-0.8, 0.8), step(0.3, 1.5);
    double x = 0, y = 0, heading = 0;
    int moves = 0;
    for (int k = 0; k < 150; ++k) {
      heading += turn(rng);
      x += step(rng) * std::cos(heading);
      y += step(rng) * std::sin(heading);
      if (std::abs(x) > 20 || std::abs(y) > 20) heading += M_PI;
      x = std::clamp(x, -25.0, 25.0), y = std::clamp(y, -25.0, 25.0);
      // Points within 1.4 m of the sensor: the box re-centres when the sensor is 2 m from its
      // centre, so every ray stays inside its 8 m.
      const Frame f = groundFrame(rng, x, y, 1.4, 150);
      moves += upd::maps::insertScan(roll, f.view(), {x, y, 0.5}, p, FusionParams{}).window_moved;
      upd::maps::insertScan(fixed, f.view(), {x, y, 0.5}, fixed_p, FusionParams{});
      expectWithinStatedCost(roll);
    }
    EXPECT_GT(moves, 10);
    EXPECT_GT(roll.keptTiles(), 0u);
    const auto whole = roll.wholeRun();
    const auto want = leaves(fixed);
    EXPECT_GT(want.size(), 5000u);
    EXPECT_EQ(leaves(*whole), want);
    roll.mergeKeptTiles();  // the same, in place
    EXPECT_EQ(roll.keptTiles(), 0u);
    EXPECT_EQ(leaves(roll), want);
    std::printf("%d-voxel tiles: %zu tiles, %zu leaves, %.1f bytes per leaf, %.0f per tile\n",
                tile_voxels, roll.keptTiles(), roll.keptLeaves(),
                double(roll.keptTileBytes()) / std::max<std::size_t>(1, roll.keptLeaves()),
                double(roll.keptTileBytes()) / std::max<std::size_t>(1, roll.keptTiles()));
  }
}

TEST(WholeRunOctree, WithoutKeepingNothingIsKeptAndTileSizeIsChecked) {
  OctreeParams p = rollingBox(32);
  p.keep_outside_box = false;
  TraversabilityOcTree tree(p);
  std::mt19937 rng(9);
  for (double x = 0; x <= 20.0; x += 1.0) {
    upd::maps::insertScan(tree, groundFrame(rng, x, 0.0, 1.4, 100).view(), {x, 0, 0.5}, p,
                          FusionParams{});
  }
  EXPECT_EQ(tree.keptTiles(), 0u);
  EXPECT_EQ(tree.wholeRun()->search(0.05, 0.05, 0.02), nullptr);
  p.tile_voxels = 100;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}
