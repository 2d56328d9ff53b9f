// The robot body and camera mount: the optical axes on the robot, the simulated intrinsics, and
// the body resting on the terrain (level on flat ground; on a tilted plane its pitch and roll
// are the plane's slope along its heading and across it, for every heading).
#include "upd/sim/robot.h"

#include <gtest/gtest.h>

#include <cmath>

namespace core = upd::core;

namespace upd::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(SimCameraMount, OpticalAxisLooksForwardAndDown) {
  CameraMountParams m;
  m.pitch_rad = 30.0 * core::kDegToRad;
  const Eigen::Isometry3d T = cameraOnRobot(m);
  const Eigen::Vector3d z_optical = T.linear().col(2);  // optical axis in the robot frame
  EXPECT_NEAR(z_optical.x(), std::cos(m.pitch_rad), 1e-12);
  EXPECT_NEAR(z_optical.y(), 0.0, 1e-12);
  EXPECT_NEAR(z_optical.z(), -std::sin(m.pitch_rad), 1e-12);
  const Eigen::Vector3d x_optical = T.linear().col(0);  // image right = robot's right
  EXPECT_NEAR(x_optical.y(), -1.0, 1e-12);
  EXPECT_NEAR(T.translation().z(), m.height_m, 1e-12);
}

TEST(SimCameraMount, MountFrameThenOpticalAxesIsTheCamera) {
  CameraMountParams m;
  m.forward_m = 0.25;
  m.left_m = -0.05;
  m.height_m = 0.6;
  for (double pitch_deg : {-30.0, 0.0, 22.0, 45.0}) {
    m.pitch_rad = pitch_deg * core::kDegToRad;
    Eigen::Isometry3d optical = Eigen::Isometry3d::Identity();
    optical.linear() = opticalInMount();
    EXPECT_TRUE((mountOnRobot(m) * optical).isApprox(cameraOnRobot(m), 1e-12)) << pitch_deg;
    // The mount's x is the optical axis (MRPT's sensor convention).
    EXPECT_TRUE(mountOnRobot(m).linear().col(0).isApprox(cameraOnRobot(m).linear().col(2), 1e-12));
  }
  EXPECT_TRUE((opticalInMount() * opticalInMount().transpose()).isIdentity(1e-15));
}

TEST(SimCameraMount, SimulatedIntrinsicsScaleTheKinect) {
  CameraMountParams m;
  EXPECT_EQ(m.image_downscale, 1);  // the Kinect itself by default
  const core::CameraIntrinsics kinect = simulatedIntrinsics(m);
  EXPECT_EQ(kinect.width, 640);
  EXPECT_EQ(kinect.cx, core::CameraIntrinsics{}.cx);
  m.image_downscale = 4;
  const core::CameraIntrinsics K = simulatedIntrinsics(m);
  EXPECT_EQ(K.width, 160);
  EXPECT_EQ(K.height, 120);
  EXPECT_NEAR(K.fx, 525.0 / 4, 1e-12);
  EXPECT_NEAR(K.cx, 79.5, 1e-12);  // still the image centre
  m.image_downscale = 3;
  EXPECT_THROW(m.validate(), std::invalid_argument);
}

TEST(SimRobotBody, BadParamsAreRejected) {
  RobotBodyParams b;
  b.track_m = 0.9;  // wider than the body
  EXPECT_THROW(b.validate(), std::invalid_argument);
  b = RobotBodyParams{};
  b.wheelbase_m = 0.0;
  EXPECT_THROW(b.validate(), std::invalid_argument);
  EXPECT_NO_THROW(RobotBodyParams{}.validate());
}

TEST(SimBodyPose, FlatGroundIsLevel) {
  const Terrain flat;
  const Eigen::Isometry3d T = bodyPoseOnTerrain(flat, {1.0, 2.0, 0.5}, RobotBodyParams{});
  EXPECT_NEAR(T.translation().z(), 0.0, 1e-12);
  EXPECT_NEAR(T.linear().col(2).z(), 1.0, 1e-12);
  EXPECT_TRUE(T.isApprox(bodyPoseFlat({1.0, 2.0, 0.5}), 1e-12));
}

// A 20 deg ramp climbing +x from x = 0, 6 m wide: a tilted plane under the whole body.
Terrain tiltedPlane(double slope_rad) {
  Terrain t({-2, -4}, {8, 4});
  Ramp r;
  r.start_xy = {0, 0};
  r.slope_rad = slope_rad;
  r.width_m = 6.0;
  r.height_m = 3.0;
  t.add(r);
  return t;
}

TEST(SimBodyPose, OnTheRampTheNoseIsUp) {
  const Terrain t = tiltedPlane(20.0 * core::kDegToRad);
  const Eigen::Isometry3d T = bodyPoseOnTerrain(t, {1.5, 0.0, 0.0}, RobotBodyParams{});
  const Eigen::Vector3d forward = T.linear().col(0);
  EXPECT_NEAR(std::atan2(forward.z(), forward.x()), 20.0 * core::kDegToRad, 1e-6);
  EXPECT_NEAR(T.translation().z(), 1.5 * std::tan(20.0 * core::kDegToRad), 1e-6);
  // Facing -y the robot's left is +x, uphill: it rolls with its left side up, not pitched.
  const Eigen::Isometry3d S = bodyPoseOnTerrain(t, {1.5, 0.0, -kPi / 2}, RobotBodyParams{});
  EXPECT_NEAR(std::asin(S.linear().col(1).z()), 20.0 * core::kDegToRad, 1e-6);
  EXPECT_NEAR(S.linear().col(0).z(), 0.0, 1e-9);
}

TEST(SimBodyPose, OnATiltedPlanePitchAndRollAreTheSlopeAlongAndAcrossTheHeading) {
  for (double slope_deg : {5.0, 15.0, 25.0}) {
    const double tan_slope = std::tan(slope_deg * core::kDegToRad);
    const Terrain t = tiltedPlane(slope_deg * core::kDegToRad);
    for (int k = 0; k < 16; ++k) {
      const double yaw = -kPi + k * kPi / 8;
      const Eigen::Isometry3d T = bodyPoseOnTerrain(t, {2.0, 0.3, yaw}, RobotBodyParams{});
      // The plane rises tan(slope) per metre along +x: along the heading by tan cos(yaw),
      // to the left by -tan sin(yaw).
      const double pitch_up = std::atan(tan_slope * std::cos(yaw));
      const double roll_left_up = std::atan(-tan_slope * std::sin(yaw));
      SCOPED_TRACE(::testing::Message() << slope_deg << " deg, yaw " << yaw);
      EXPECT_NEAR(std::asin(T.linear().col(0).z()), pitch_up, 1e-9);
      // Rz(yaw) Ry(pitch) Rx(roll): the body's y axis rises by cos(pitch) sin(roll).
      const double pitch = -pitch_up;
      EXPECT_NEAR(T.linear().col(1).z(), std::cos(pitch) * std::sin(roll_left_up), 1e-9);
      EXPECT_NEAR(T.translation().z(), 2.0 * tan_slope,
                  1e-9);  // the mean of the wheels: the centre
      // Heading is kept: the body's x projects onto the yaw direction.
      EXPECT_NEAR(std::atan2(T.linear()(1, 0), T.linear()(0, 0)), yaw, 1e-9);
    }
  }
}

}  // namespace
}  // namespace upd::sim
