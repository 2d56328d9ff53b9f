#include "upd/sim/robot.h"

#include <cmath>

namespace upd::sim {

void RobotBodyParams::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  core::requireParam(positive(length_m), "RobotBodyParams", "length_m", length_m, "must be > 0");
  core::requireParam(positive(width_m), "RobotBodyParams", "width_m", width_m, "must be > 0");
  core::requireParam(positive(wheelbase_m) && wheelbase_m <= length_m, "RobotBodyParams", "wheelbase_m",
               wheelbase_m, "must be in (0, length_m]");
  core::requireParam(positive(track_m) && track_m <= width_m, "RobotBodyParams", "track_m", track_m,
               "must be in (0, width_m]");
}

void CameraMountParams::validate() const {
  core::requireParam(std::isfinite(forward_m), "CameraMountParams", "forward_m", forward_m,
               "must be finite");
  core::requireParam(std::isfinite(left_m), "CameraMountParams", "left_m", left_m, "must be finite");
  core::requireParam(std::isfinite(height_m) && height_m > 0, "CameraMountParams", "height_m", height_m,
               "must be > 0");
  core::requireParam(std::isfinite(pitch_rad) && std::abs(pitch_rad) < 80.0 * core::kDegToRad,
               "CameraMountParams", "pitch_deg", pitch_rad * core::kRadToDeg,
               "must be within (-80, 80) deg");
  core::requireParam(std::isfinite(roll_rad) && std::abs(roll_rad) < 80.0 * core::kDegToRad,
               "CameraMountParams", "roll_deg", roll_rad * core::kRadToDeg,
               "must be within (-80, 80) deg");
  core::requireParam(
      image_downscale == 1 || image_downscale == 2 || image_downscale == 4 || image_downscale == 8,
      "CameraMountParams", "image_downscale", image_downscale, "must be 1, 2, 4 or 8");
}

Eigen::Isometry3d mountOnRobot(const CameraMountParams& mount) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(mount.forward_m, mount.left_m, mount.height_m);
  // A pitch > 0 about y turns +x towards -z: the camera looks down; then a roll > 0 about the
  // (pitched) optical axis turns the left side up.
  T.linear() = (Eigen::AngleAxisd(mount.pitch_rad, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(mount.roll_rad, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

Eigen::Matrix3d opticalInMount() {
  // The optical z is forward (+x), x is right (-y), y is down (-z).
  Eigen::Matrix3d m;
  m.col(0) = -Eigen::Vector3d::UnitY();
  m.col(1) = -Eigen::Vector3d::UnitZ();
  m.col(2) = Eigen::Vector3d::UnitX();
  return m;
}

Eigen::Isometry3d cameraOnRobot(const CameraMountParams& mount) {
  // The optical axes of a level camera looking along the robot's x, pitched and rolled as
  // mountOnRobot.
  Eigen::Isometry3d T = mountOnRobot(mount);
  T.linear() = T.linear() * opticalInMount();
  return T;
}

core::CameraIntrinsics simulatedIntrinsics(const CameraMountParams& mount) {
  const core::CameraIntrinsics kinect;
  const double d = mount.image_downscale;
  core::CameraIntrinsics K;
  K.width = kinect.width / mount.image_downscale;
  K.height = kinect.height / mount.image_downscale;
  K.fx = kinect.fx / d;
  K.fy = kinect.fy / d;
  // Pixel centres: a coarse pixel covers d fine ones.
  K.cx = (kinect.cx + 0.5) / d - 0.5;
  K.cy = (kinect.cy + 0.5) / d - 0.5;
  return K;
}

Eigen::Isometry3d bodyPoseOnTerrain(const Terrain& terrain, const Eigen::Vector3d& xy_yaw,
                                    const RobotBodyParams& body) {
  const double hx = 0.5 * body.wheelbase_m, hy = 0.5 * body.track_m;
  const double c = std::cos(xy_yaw.z()), s = std::sin(xy_yaw.z());
  const auto h = [&](double u, double v) {  // the height under robot-frame (u, v)
    return terrain.heightAt(xy_yaw.x() + c * u - s * v, xy_yaw.y() + s * u + c * v);
  };
  const double fl = h(hx, hy), fr = h(hx, -hy), rl = h(-hx, hy), rr = h(-hx, -hy);
  const double z = 0.25 * (fl + fr + rl + rr);
  const double rise_front = 0.5 * (fl + fr) - 0.5 * (rl + rr);
  const double rise_left = 0.5 * (fl + rl) - 0.5 * (fr + rr);
  // Nose up is a negative rotation about y; left side up a positive rotation about x.
  const double pitch = -std::atan2(rise_front, body.wheelbase_m);
  const double roll = std::atan2(rise_left, body.track_m);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(xy_yaw.z(), Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(xy_yaw.x(), xy_yaw.y(), z);
  return T;
}

Eigen::Isometry3d bodyPoseFlat(const Eigen::Vector3d& xy_yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(xy_yaw.z(), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(xy_yaw.x(), xy_yaw.y(), 0.0);
  return T;
}

core::PointCloud renderCameraWorld(const Terrain& terrain, const Eigen::Isometry3d& pose_world_body,
                             const CameraMountParams& mount, const DepthNoise& noise,
                             std::uint32_t seed) {
  const Eigen::Isometry3d pose_world_camera = pose_world_body * cameraOnRobot(mount);
  const core::CameraIntrinsics K = simulatedIntrinsics(mount);
  const core::DepthImage depth = renderDepth(terrain, pose_world_camera, K, noise, seed);
  return core::transformCloud(core::depthToCloud(depth, K), pose_world_camera);
}

}  // namespace upd::sim
