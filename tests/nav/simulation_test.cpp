// The simulated world around the loop: body on the terrain, camera mount, ground-truth checks,
// and missing-ground detection on rendered frames.
#include "upd/nav/negative_obstacles.h"
#include "upd/nav/simulation.h"

#include <gtest/gtest.h>

#include <cmath>

namespace upd::nav {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(NavCameraMount, OpticalAxisLooksForwardAndDown) {
  CameraMountParams m;
  m.pitch_rad = 30.0 * kDegToRad;
  const Eigen::Isometry3d T = cameraOnRobot(m);
  const Eigen::Vector3d z_optical = T.linear().col(2);  // optical axis in the robot frame
  EXPECT_NEAR(z_optical.x(), std::cos(m.pitch_rad), 1e-12);
  EXPECT_NEAR(z_optical.y(), 0.0, 1e-12);
  EXPECT_NEAR(z_optical.z(), -std::sin(m.pitch_rad), 1e-12);
  const Eigen::Vector3d x_optical = T.linear().col(0);  // image right = robot's right
  EXPECT_NEAR(x_optical.y(), -1.0, 1e-12);
  EXPECT_NEAR(T.translation().z(), m.height_m, 1e-12);
}

TEST(NavCameraMount, SimulatedIntrinsicsScaleTheKinect) {
  CameraMountParams m;
  m.image_downscale = 4;
  const CameraIntrinsics K = simulatedIntrinsics(m);
  EXPECT_EQ(K.width, 160);
  EXPECT_EQ(K.height, 120);
  EXPECT_NEAR(K.fx, 525.0 / 4, 1e-12);
  EXPECT_NEAR(K.cx, 79.5, 1e-12);  // still the image centre
  m.image_downscale = 3;
  EXPECT_THROW(m.validate(), std::invalid_argument);
}

TEST(NavBodyPose, FlatGroundIsLevel) {
  const Terrain flat;
  const Eigen::Isometry3d T = bodyPoseOnTerrain(flat, {1.0, 2.0, 0.5}, RobotBodyParams{});
  EXPECT_NEAR(T.translation().z(), 0.0, 1e-12);
  EXPECT_NEAR(T.linear().col(2).z(), 1.0, 1e-12);
  EXPECT_TRUE(T.isApprox(bodyPoseFlat({1.0, 2.0, 0.5}), 1e-12));
}

TEST(NavBodyPose, OnTheRampTheNoseIsUp) {
  // A 20 deg ramp climbing +x from x = 0, 3 m wide: the robot in its middle facing uphill.
  Terrain t({-2, -2}, {6, 2});
  Ramp r;
  r.start_xy = {0, 0};
  r.slope_rad = 20.0 * kDegToRad;
  r.width_m = 3.0;
  r.height_m = 1.0;
  t.add(r);
  const Eigen::Isometry3d T = bodyPoseOnTerrain(t, {1.5, 0.0, 0.0}, RobotBodyParams{});
  const Eigen::Vector3d forward = T.linear().col(0);
  EXPECT_NEAR(std::atan2(forward.z(), forward.x()), 20.0 * kDegToRad, 1e-6);
  EXPECT_NEAR(T.translation().z(), 1.5 * std::tan(20.0 * kDegToRad), 1e-6);
  // Facing -y the robot's left is +x, uphill: it rolls with its left side up, not pitched.
  const Eigen::Isometry3d S = bodyPoseOnTerrain(t, {1.5, 0.0, -kPi / 2}, RobotBodyParams{});
  EXPECT_NEAR(std::asin(S.linear().col(1).z()), 20.0 * kDegToRad, 1e-6);
  EXPECT_NEAR(S.linear().col(0).z(), 0.0, 1e-9);
}

TEST(NavTruthRaster, CollisionAndClearanceAgainstAWall) {
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
  // Far away: capped at the search distance.
  EXPECT_EQ(truth.clearance({0.5, 0.0, kPi}, body, 1.0), 1.0);
}

TEST(NavMissingGround, TheDitchIsFoundAndFlatGroundIsNot) {
  const WorldSpec ditch = makeWorld("ditch");
  const CameraMountParams mount;
  DepthNoise noise;
  // Facing the ditch (x 4.7..5.3) from 2.2 m before it.
  const PointCloud seen = renderCameraWorld(
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
  const Terrain flat({0, -4}, {10, 4});
  const PointCloud plain = renderCameraWorld(flat, bodyPoseFlat({2.5, -1.0, 0.0}), mount, noise, 3);
  EXPECT_TRUE(findGroundGaps(plain, 0.0, NegativeObstacleParams{}).empty());
}

TEST(NavMissingGround, TheShadowBehindAPlatformIsNotAGap) {
  // From the ground the platform's top hides the ground behind it, which lies lower than the top
  // but not lower than the robot: a positive obstacle's shadow, not missing ground.
  const WorldSpec ramp = makeWorld("ramp");
  const PointCloud seen = renderCameraWorld(
      ramp.terrain, bodyPoseOnTerrain(ramp.terrain, {3.5, 0.5, 0.0}, RobotBodyParams{}),
      CameraMountParams{}, DepthNoise{}, 5);
  EXPECT_TRUE(findGroundGaps(seen, 0.0, NegativeObstacleParams{}).empty());
}

}  // namespace
}  // namespace upd::nav
