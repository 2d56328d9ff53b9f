// The rasterised ground truth: its cells hold Terrain::truthAt at their centres; a footprint
// against a wall collides or keeps its clearance.
#include "upd/sim/truth_raster.h"

#include <gtest/gtest.h>

#include <cmath>

namespace core = upd::core;

namespace upd::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(SimTruthRaster, CellsHoldTheTruthAtTheirCentres) {
  const WorldSpec world = makeWorld("mixed");
  const TruthRaster truth(world.terrain, 0.1);
  EXPECT_EQ(truth.sizeX(), 120);
  EXPECT_EQ(truth.sizeY(), 80);
  EXPECT_TRUE(truth.origin().isApprox(world.terrain.minXY()));
  ASSERT_EQ(truth.labels().size(), 120u * 80u);
  std::size_t non_traversable = 0;
  for (int iy = 0; iy < truth.sizeY(); ++iy) {
    for (int ix = 0; ix < truth.sizeX(); ++ix) {
      const Eigen::Vector2d c = truth.cellCenter(ix, iy);
      EXPECT_NEAR(c.x(), (ix + 0.5) * 0.1, 1e-12);
      ASSERT_EQ(truth.at(ix, iy), world.terrain.truthAt(c.x(), c.y()));
      non_traversable += truth.at(ix, iy) == core::Label::NonTraversable;
    }
  }
  EXPECT_GT(non_traversable, 100u);
  EXPECT_THROW(TruthRaster(world.terrain, 0.0), std::invalid_argument);
}

TEST(SimTruthRaster, CollisionAndClearanceAgainstAWall) {
  Terrain t({0, -2}, {6, 2});
  Box wall;
  wall.center_xy = {3.0, 0.0};
  wall.length_m = 0.2;
  wall.width_m = 4.0;
  wall.height_m = 0.8;
  wall.wall = true;
  t.add(wall);
  const TruthRaster truth(t, 0.025);
  const RobotBodyParams body;
  // The wall's truth covers x in [2.85, 3.15] (0.05 m band). A robot centred at x = 2 facing +x
  // has its front at 2.35: 0.5 m away.
  EXPECT_NEAR(truth.clearance({2.0, 0.0, 0.0}, body, 2.0), 0.5, 0.03);
  EXPECT_FALSE(truth.collides({2.0, 0.0, 0.0}, body));
  EXPECT_TRUE(truth.collides({2.6, 0.0, 0.0}, body));
  EXPECT_EQ(truth.clearance({2.6, 0.0, 0.0}, body, 2.0), 0.0);
  // Turned by 90 deg the body's half-width (0.225 m) faces the wall: 0.625 m away.
  EXPECT_NEAR(truth.clearance({2.0, 0.0, kPi / 2}, body, 2.0), 0.625, 0.03);
  // Far away: capped at the search distance.
  EXPECT_EQ(truth.clearance({0.5, 0.0, kPi}, body, 1.0), 1.0);
}

}  // namespace
}  // namespace upd::sim
