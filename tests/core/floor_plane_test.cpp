// The floor under a camera: a tilted, raised camera over a synthetic floor with clutter gets its
// height, pitch and roll back; no floor in view is reported, not guessed.
#include "upd/core/floor_plane.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <random>

namespace upd::core {
namespace {

constexpr double kDeg = kDegToRad;

// camera-optical -> world (z up) for a camera at height h, pitched and rolled as the header
// says (the optical axes: x right, y down, z forward).
Eigen::Isometry3d cameraInWorld(double h, double pitch, double roll) {
  Eigen::Matrix3d optical_in_mount;
  optical_in_mount.col(0) = -Eigen::Vector3d::UnitY();
  optical_in_mount.col(1) = -Eigen::Vector3d::UnitZ();
  optical_in_mount.col(2) = Eigen::Vector3d::UnitX();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix() *
               optical_in_mount;
  T.translation() = Eigen::Vector3d(0, 0, h);
  return T;
}

struct SceneOptions {
  bool floor = true;
  int clutter = 6000;  // points on boxes, a wall and in the air
};

// A world (floor z = 0 with 5 mm noise, boxes, a wall, scattered points) seen by the camera:
// the points in front of it, in its optical frame.
PointCloud scene(const Eigen::Isometry3d& camera_in_world, std::uint32_t seed,
                 SceneOptions opt = {}) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, 0.005);
  std::vector<Eigen::Vector3d> world;
  if (opt.floor) {
    for (int i = 0; i < 20000; ++i) world.emplace_back(0.3 + 5 * u(rng), -3 + 6 * u(rng), noise(rng));
  }
  for (int i = 0; i < opt.clutter; ++i) {
    const double r = u(rng);
    if (r < 0.4) {  // a 0.4 m bush at x ~ 2 (points through its volume)
      world.emplace_back(1.8 + 0.4 * u(rng), -0.2 + 0.4 * u(rng), 0.4 * u(rng));
    } else if (r < 0.8) {  // a wall at x = 5.3
      world.emplace_back(5.3 + noise(rng), -3 + 6 * u(rng), 2.5 * u(rng));
    } else {  // in the air
      world.emplace_back(0.5 + 4 * u(rng), -2 + 4 * u(rng), 2 * u(rng));
    }
  }
  const Eigen::Isometry3d world_to_camera = camera_in_world.inverse();
  PointCloud c;
  for (const auto& w : world) {
    const Eigen::Vector3d p = world_to_camera * w;
    if (p.z() > 0.2) c.push_back(float(p.x()), float(p.y()), float(p.z()));
  }
  return c;
}

TEST(FloorPlane, RecoversHeightPitchRollOfManyMounts) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> height(0.25, 1.6), pitch(-10, 45), roll(-12, 12);
  for (int k = 0; k < 12; ++k) {
    const double h = height(rng), p = pitch(rng) * kDeg, r = roll(rng) * kDeg;
    const PointCloud cloud = scene(cameraInWorld(h, p, r), 100 + k);
    const FloorPlane floor = fitFloorPlane({&cloud}, FloorPlaneParams{});
    ASSERT_TRUE(floor.found) << floor.failure << " (mount " << k << ")";
    const MountPose m = mountFromFloor(floor);
    EXPECT_NEAR(m.height_m, h, 0.01) << "mount " << k;
    EXPECT_NEAR(m.pitch_rad, p, 0.5 * kDeg) << "mount " << k;
    EXPECT_NEAR(m.roll_rad, r, 0.5 * kDeg) << "mount " << k;
    EXPECT_LT(floor.rms_residual_m, 0.01);
    EXPECT_GT(floor.inlierShare(), 0.3);
    EXPECT_LE(floor.inlierShare(), 1.0);
  }
}

TEST(FloorPlane, NormalOfTheMountAnglesIsTheFloorNormalInTheCamera) {
  for (double p : {-20.0, 0.0, 22.0, 50.0}) {
    for (double r : {-15.0, 0.0, 8.0}) {
      const Eigen::Isometry3d T = cameraInWorld(0.5, p * kDeg, r * kDeg);
      const Eigen::Vector3d up_in_camera = T.linear().transpose() * Eigen::Vector3d::UnitZ();
      EXPECT_TRUE(floorNormalInCamera(p * kDeg, r * kDeg).isApprox(up_in_camera, 1e-12));
    }
  }
}

TEST(FloorPlane, SeveralFramesGiveTheSameMountAsOne) {
  const Eigen::Isometry3d T = cameraInWorld(0.5, 0, 0);
  const PointCloud a = scene(T, 1), b = scene(T, 2), c = scene(T, 3);
  const FloorPlane one = fitFloorPlane({&a}, FloorPlaneParams{});
  const FloorPlane three = fitFloorPlane({&a, &b, &c}, FloorPlaneParams{});
  ASSERT_TRUE(one.found && three.found);
  EXPECT_EQ(three.valid_points, a.size() + b.size() + c.size());
  EXPECT_NEAR(mountFromFloor(three).height_m, 0.5, 0.005);
  EXPECT_NEAR(mountFromFloor(three).pitch_rad, mountFromFloor(one).pitch_rad, 0.3 * kDeg);
}

TEST(FloorPlane, SameInputSameSeedSamePlane) {
  const PointCloud a = scene(cameraInWorld(0.8, 30 * kDeg, 3 * kDeg), 5);
  const FloorPlane f1 = fitFloorPlane({&a}, FloorPlaneParams{});
  const FloorPlane f2 = fitFloorPlane({&a}, FloorPlaneParams{});
  EXPECT_EQ(f1.normal, f2.normal);
  EXPECT_EQ(f1.inliers, f2.inliers);
}

TEST(FloorPlane, NoFloorIsReportedNotGuessed) {
  SceneOptions no_floor;
  no_floor.floor = false;
  const PointCloud clutter = scene(cameraInWorld(0.5, 0, 0), 3, no_floor);
  const FloorPlane f = fitFloorPlane({&clutter}, FloorPlaneParams{});
  EXPECT_FALSE(f.found);
  EXPECT_FALSE(f.failure.empty());

  const PointCloud empty;
  const FloorPlane e = fitFloorPlane({&empty}, FloorPlaneParams{});
  EXPECT_FALSE(e.found);
  EXPECT_EQ(e.valid_points, 0u);

  // A camera looking straight at a wall: only a vertical plane, far outside the tilt bound.
  PointCloud wall;
  for (int i = 0; i < 100; ++i) {
    for (int j = 0; j < 100; ++j) wall.push_back(-1 + 0.02f * i, -1 + 0.02f * j, 2.f);
  }
  EXPECT_FALSE(fitFloorPlane({&wall}, FloorPlaneParams{}).found);
}

TEST(FloorPlane, NanPointsAreIgnored) {
  PointCloud c = scene(cameraInWorld(0.6, 10 * kDeg, 0), 9);
  const std::size_t finite = c.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int i = 0; i < 1000; ++i) c.push_back(nan, nan, nan);
  const FloorPlane f = fitFloorPlane({&c}, FloorPlaneParams{});
  ASSERT_TRUE(f.found);
  EXPECT_EQ(f.valid_points, finite);
  EXPECT_NEAR(mountFromFloor(f).height_m, 0.6, 0.01);
}

TEST(FloorPlane, BadParamsThrowNamingTheField) {
  FloorPlaneParams p;
  p.inlier_distance_m = 0;
  try {
    p.validate();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("FloorPlaneParams.inlier_distance_m"), std::string::npos);
  }
}

}  // namespace
}  // namespace upd::core
