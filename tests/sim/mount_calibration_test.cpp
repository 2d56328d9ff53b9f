// The mount measured from a rendered floor: a camera pitched and rolled on the simulated robot
// gets its mount back; the convention of CameraMountParams' roll agrees with the floor plane's;
// no floor in view stops a run that needs the mount.
#include "upd/sim/mount_calibration.h"
#include "upd/sim/render.h"
#include "upd/sim/robot.h"
#include "upd/sim/terrain.h"

#include <gtest/gtest.h>

namespace upd::sim {
namespace {

constexpr double kDeg = core::kDegToRad;

core::PointCloud frameInCamera(const Terrain& world, const CameraMountParams& mount) {
  const Eigen::Isometry3d pose = bodyPoseFlat({-3, 0, 0}) * cameraOnRobot(mount);
  const core::CameraIntrinsics K = simulatedIntrinsics(mount);
  return core::depthToCloud(renderDepth(world, pose, K, DepthNoise{}, 5), K);
}

TEST(MountCalibration, RenderedFloorGivesTheMountBack) {
  Terrain world;
  Box box;
  box.center_xy = {-1, 0.5};
  box.height_m = 0.4;
  world.add(box);
  CameraMountParams configured;  // 0.5 m, 22 deg down: the prior
  configured.image_downscale = 4;
  for (double pitch : {0.0, 15.0, 35.0}) {
    for (double roll : {-6.0, 0.0, 4.0}) {
      CameraMountParams truth = configured;
      truth.height_m = 0.35 + pitch / 100;
      truth.pitch_rad = pitch * kDeg;
      truth.roll_rad = roll * kDeg;
      const core::PointCloud cloud = frameInCamera(world, truth);
      const MountCalibration c = calibrateMount({&cloud}, configured);
      ASSERT_TRUE(c.ok()) << c.summary();
      EXPECT_NEAR(c.mount.height_m, truth.height_m, 0.01) << c.summary();
      EXPECT_NEAR(c.mount.pitch_rad, truth.pitch_rad, 0.5 * kDeg) << c.summary();
      EXPECT_NEAR(c.mount.roll_rad, truth.roll_rad, 0.5 * kDeg) << c.summary();
      EXPECT_EQ(c.mount.forward_m, configured.forward_m);  // not measured: kept
    }
  }
}

TEST(MountCalibration, RollOfTheMountIsTheFloorPlanesRoll) {
  CameraMountParams m;
  m.pitch_rad = 12 * kDeg;
  m.roll_rad = -7 * kDeg;
  const Eigen::Vector3d up_in_camera = cameraOnRobot(m).linear().transpose() * Eigen::Vector3d::UnitZ();
  EXPECT_TRUE(up_in_camera.isApprox(core::floorNormalInCamera(m.pitch_rad, m.roll_rad), 1e-12));
  // cameraOnRobot is mountOnRobot followed by the optical axes.
  EXPECT_TRUE(cameraOnRobot(m).linear().isApprox(mountOnRobot(m).linear() * opticalInMount(), 1e-12));
  m.roll_rad = 85 * kDeg;
  EXPECT_THROW(m.validate(), std::invalid_argument);
}

TEST(MountCalibration, NoFloorInViewStopsTheRun) {
  const Terrain world;
  CameraMountParams up;  // looking 60 deg up: sky only
  up.pitch_rad = -60 * kDeg;
  up.image_downscale = 4;
  const core::PointCloud sky = frameInCamera(world, up);
  EXPECT_FALSE(calibrateMount({&sky}, CameraMountParams{}).ok());
  try {
    requireCalibratedMount({&sky}, CameraMountParams{});
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no floor found in 1 frame"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not navigating"), std::string::npos) << e.what();
  }
}

TEST(MountCalibration, IniSectionHoldsEveryKeyInDegrees) {
  CameraMountParams m;
  m.height_m = 0.42;
  m.pitch_rad = 10 * kDeg;
  m.roll_rad = -2 * kDeg;
  const std::string s = mountIniSection(m, "measured");
  EXPECT_EQ(s.rfind("; measured\n[CameraMountParams]\n", 0), 0u) << s;
  for (const char* k : {"forward_m = 0.3", "left_m = 0", "height_m = 0.42", "pitch_deg = 10",
                        "roll_deg = -2", "image_downscale = 1"}) {
    EXPECT_NE(s.find(std::string("\n") + k + "\n"), std::string::npos) << k << " in\n" << s;
  }
}

}  // namespace
}  // namespace upd::sim
