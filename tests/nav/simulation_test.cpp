// Missing-ground detection on frames rendered from the simulated robot (upd/sim/robot.h):
// the ditch is found, flat ground and a platform's shadow are not. The robot and camera
// themselves are tested in tests/sim/robot_test.cpp, the truth raster in truth_raster_test.cpp.
#include "upd/nav/negative_obstacles.h"
#include "upd/sim/robot.h"

#include <gtest/gtest.h>

#include <cmath>

namespace core = upd::core;

namespace upd::nav {
namespace {

using sim::bodyPoseFlat;
using sim::bodyPoseOnTerrain;
using sim::CameraMountParams;
using sim::DepthNoise;
using sim::renderCameraWorld;
using sim::RobotBodyParams;

// The navigation loop's camera: 160 x 120 (config/dune-nav.ini).
CameraMountParams navCamera() {
  CameraMountParams m;
  m.image_downscale = 4;
  return m;
}

TEST(NavMissingGround, TheDitchIsFoundAndFlatGroundIsNot) {
  const sim::WorldSpec ditch = sim::makeWorld("ditch");
  const CameraMountParams mount = navCamera();
  DepthNoise noise;
  // Facing the ditch (x 4.7..5.3) from 2.2 m before it.
  const core::PointCloud seen = renderCameraWorld(
      ditch.terrain, bodyPoseOnTerrain(ditch.terrain, {2.5, -1.0, 0.0}, RobotBodyParams{}), mount,
      noise, 3);
  const auto gaps = findGroundGaps(seen, 0.0, NegativeObstacleParams{});
  ASSERT_GT(gaps.size(), 20u);
  for (const auto& g : gaps) {
    // Near side on the rim, far side on the far wall or floor: the hidden ground in between.
    EXPECT_NEAR(g.near_world.x(), 4.7, 0.1);
    EXPECT_GT(g.far_world.x(), 4.75);
    EXPECT_LT(g.far_world.x(), 5.35);
    EXPECT_LT(g.far_world.z(), g.near_world.z() - 0.08);
    for (const auto& p : sampleGap(g, 0.05)) {
      EXPECT_GT(p.x(), 4.6);
      EXPECT_LT(p.x(), 5.35);
    }
  }
  const sim::Terrain flat({0, -4}, {10, 4});
  const core::PointCloud plain = renderCameraWorld(flat, bodyPoseFlat({2.5, -1.0, 0.0}), mount, noise, 3);
  EXPECT_TRUE(findGroundGaps(plain, 0.0, NegativeObstacleParams{}).empty());
}

TEST(NavMissingGround, TheShadowBehindAPlatformIsNotAGap) {
  // From the ground the platform's top hides the ground behind it, which lies lower than the top
  // but not lower than the robot: a positive obstacle's shadow, not missing ground.
  const sim::WorldSpec ramp = sim::makeWorld("ramp");
  const core::PointCloud seen = renderCameraWorld(
      ramp.terrain, bodyPoseOnTerrain(ramp.terrain, {3.5, 0.5, 0.0}, RobotBodyParams{}),
      navCamera(), DepthNoise{}, 5);
  EXPECT_TRUE(findGroundGaps(seen, 0.0, NegativeObstacleParams{}).empty());
}

}  // namespace
}  // namespace upd::nav
