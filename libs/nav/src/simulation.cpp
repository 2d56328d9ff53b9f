#include "upd/nav/simulation.h"

#include "upd/nav/obstacles.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace upd::nav {

void RobotBodyParams::validate() const {
  const auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  requireParam(positive(length_m), "RobotBodyParams", "length_m", length_m, "must be > 0");
  requireParam(positive(width_m), "RobotBodyParams", "width_m", width_m, "must be > 0");
  requireParam(positive(wheelbase_m) && wheelbase_m <= length_m, "RobotBodyParams", "wheelbase_m",
               wheelbase_m, "must be in (0, length_m]");
  requireParam(positive(track_m) && track_m <= width_m, "RobotBodyParams", "track_m", track_m,
               "must be in (0, width_m]");
}

void CameraMountParams::validate() const {
  requireParam(std::isfinite(forward_m), "CameraMountParams", "forward_m", forward_m,
               "must be finite");
  requireParam(std::isfinite(left_m), "CameraMountParams", "left_m", left_m, "must be finite");
  requireParam(std::isfinite(height_m) && height_m > 0, "CameraMountParams", "height_m", height_m,
               "must be > 0");
  requireParam(std::isfinite(pitch_rad) && std::abs(pitch_rad) < 80.0 * kDegToRad,
               "CameraMountParams", "pitch_deg", pitch_rad * kRadToDeg,
               "must be within (-80, 80) deg");
  requireParam(
      image_downscale == 1 || image_downscale == 2 || image_downscale == 4 || image_downscale == 8,
      "CameraMountParams", "image_downscale", image_downscale, "must be 1, 2, 4 or 8");
}

Eigen::Isometry3d cameraOnRobot(const CameraMountParams& mount) {
  // Optical axes in the robot frame for a level camera looking along the robot's x: the optical
  // z is forward (+x), x is right (-y), y is down (-z). Pitching down rotates about the robot's
  // y by +pitch (which tips +x towards -z).
  Eigen::Matrix3d level;
  level.col(0) = -Eigen::Vector3d::UnitY();
  level.col(1) = -Eigen::Vector3d::UnitZ();
  level.col(2) = Eigen::Vector3d::UnitX();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(mount.pitch_rad, Eigen::Vector3d::UnitY()).toRotationMatrix() * level;
  T.translation() = Eigen::Vector3d(mount.forward_m, mount.left_m, mount.height_m);
  return T;
}

CameraIntrinsics simulatedIntrinsics(const CameraMountParams& mount) {
  const CameraIntrinsics kinect;
  const double d = mount.image_downscale;
  CameraIntrinsics K;
  K.width = kinect.width / mount.image_downscale;
  K.height = kinect.height / mount.image_downscale;
  K.fx = kinect.fx / d;
  K.fy = kinect.fy / d;
  // Pixel centres: a coarse pixel covers d fine ones.
  K.cx = (kinect.cx + 0.5) / d - 0.5;
  K.cy = (kinect.cy + 0.5) / d - 0.5;
  return K;
}

Eigen::Isometry3d bodyPoseOnTerrain(const Terrain& terrain, const Pose2D& pose_world_robot,
                                    const RobotBodyParams& body) {
  const double hx = 0.5 * body.wheelbase_m, hy = 0.5 * body.track_m;
  const auto h = [&](double u, double v) {
    const Eigen::Vector2d p = robotToWorld(pose_world_robot, {u, v});
    return terrain.heightAt(p.x(), p.y());
  };
  const double fl = h(hx, hy), fr = h(hx, -hy), rl = h(-hx, hy), rr = h(-hx, -hy);
  const double z = 0.25 * (fl + fr + rl + rr);
  const double rise_front = 0.5 * (fl + fr) - 0.5 * (rl + rr);
  const double rise_left = 0.5 * (fl + rl) - 0.5 * (fr + rr);
  // Nose up is a negative rotation about y; left side up a positive rotation about x.
  const double pitch = -std::atan2(rise_front, body.wheelbase_m);
  const double roll = std::atan2(rise_left, body.track_m);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = (Eigen::AngleAxisd(pose_world_robot.yaw_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(pose_world_robot.x_m, pose_world_robot.y_m, z);
  return T;
}

Eigen::Isometry3d bodyPoseFlat(const Pose2D& pose_world_robot) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(pose_world_robot.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(pose_world_robot.x_m, pose_world_robot.y_m, 0.0);
  return T;
}

PointCloud renderCameraWorld(const Terrain& terrain, const Eigen::Isometry3d& pose_world_body,
                             const CameraMountParams& mount, const DepthNoise& noise,
                             std::uint32_t seed) {
  const Eigen::Isometry3d pose_world_camera = pose_world_body * cameraOnRobot(mount);
  const CameraIntrinsics K = simulatedIntrinsics(mount);
  const DepthImage depth = renderDepth(terrain, pose_world_camera, K, noise, seed);
  return transformCloud(depthToCloud(depth, K), pose_world_camera);
}

TruthRaster::TruthRaster(const Terrain& terrain, double cell_m)
    : min_xy_(terrain.minXY()), cell_m_(cell_m) {
  if (!(cell_m > 0) || !std::isfinite(cell_m)) {
    throw std::invalid_argument("TruthRaster: cell_m = " + std::to_string(cell_m) +
                                ": must be > 0");
  }
  const Eigen::Vector2d ext = terrain.maxXY() - terrain.minXY();
  nx_ = std::max(1, static_cast<int>(std::ceil(ext.x() / cell_m)));
  ny_ = std::max(1, static_cast<int>(std::ceil(ext.y() / cell_m)));
  labels_.resize(static_cast<std::size_t>(nx_) * ny_);
  for (int iy = 0; iy < ny_; ++iy) {
    for (int ix = 0; ix < nx_; ++ix) {
      const Eigen::Vector2d c = cellCenter(ix, iy);
      labels_[static_cast<std::size_t>(iy) * nx_ + ix] = terrain.truthAt(c.x(), c.y());
    }
  }
}

Eigen::Vector2d TruthRaster::cellCenter(int ix, int iy) const {
  return min_xy_ + Eigen::Vector2d((ix + 0.5) * cell_m_, (iy + 0.5) * cell_m_);
}

namespace {

// Distance from p_robot to the footprint rectangle (0 inside).
double distanceToFootprint(const Eigen::Vector2d& p_robot, const RobotBodyParams& body) {
  const double dx = std::max(0.0, std::abs(p_robot.x()) - 0.5 * body.length_m);
  const double dy = std::max(0.0, std::abs(p_robot.y()) - 0.5 * body.width_m);
  return std::hypot(dx, dy);
}

}  // namespace

double TruthRaster::clearance(const Pose2D& pose_world_robot, const RobotBodyParams& body,
                              double search_m) const {
  const double reach = 0.5 * std::hypot(body.length_m, body.width_m) + search_m;
  const int ix0 = std::max(
      0, static_cast<int>(std::floor((pose_world_robot.x_m - reach - min_xy_.x()) / cell_m_)));
  const int iy0 = std::max(
      0, static_cast<int>(std::floor((pose_world_robot.y_m - reach - min_xy_.y()) / cell_m_)));
  const int ix1 = std::min(
      nx_ - 1,
      static_cast<int>(std::floor((pose_world_robot.x_m + reach - min_xy_.x()) / cell_m_)));
  const int iy1 = std::min(
      ny_ - 1,
      static_cast<int>(std::floor((pose_world_robot.y_m + reach - min_xy_.y()) / cell_m_)));
  double best = search_m;
  for (int iy = iy0; iy <= iy1; ++iy) {
    for (int ix = ix0; ix <= ix1; ++ix) {
      if (at(ix, iy) != Label::NonTraversable) continue;
      const double d =
          distanceToFootprint(worldToRobot(pose_world_robot, cellCenter(ix, iy)), body);
      best = std::min(best, d);
    }
  }
  return best;
}

bool TruthRaster::collides(const Pose2D& pose_world_robot, const RobotBodyParams& body) const {
  return clearance(pose_world_robot, body, cell_m_) <= 0.0;
}

}  // namespace upd::nav
