#include "upd/sim/mount_calibration.h"

#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace upd::sim {

std::string MountCalibration::summary() const {
  char buf[320];
  if (!ok()) {
    std::snprintf(buf, sizeof buf, "no floor found in %zu frame%s: %s", frames,
                  frames == 1 ? "" : "s", floor.failure.c_str());
    return buf;
  }
  std::snprintf(buf, sizeof buf,
                "floor found in %zu frame%s: height %.3f m, pitch %.2f deg, roll %.2f deg, "
                "residual %.4f m, %.1f %% of the points on the plane",
                frames, frames == 1 ? "" : "s", mount.height_m, mount.pitch_rad * core::kRadToDeg,
                mount.roll_rad * core::kRadToDeg, floor.rms_residual_m,
                100.0 * floor.inlierShare());
  return buf;
}

MountCalibration calibrateMount(const std::vector<const core::PointCloud*>& clouds_in_camera,
                                const CameraMountParams& configured,
                                const core::FloorPlaneParams& params) {
  MountCalibration c;
  c.frames = clouds_in_camera.size();
  c.mount = configured;
  const Eigen::Vector3d up_prior =
      core::floorNormalInCamera(configured.pitch_rad, configured.roll_rad);
  c.floor = core::fitFloorPlane(clouds_in_camera, params, up_prior);
  if (!c.floor.found) return c;
  const core::MountPose m = core::mountFromFloor(c.floor);
  c.mount.height_m = m.height_m;
  c.mount.pitch_rad = m.pitch_rad;
  c.mount.roll_rad = m.roll_rad;
  return c;
}

MountCalibration requireCalibratedMount(
    const std::vector<const core::PointCloud*>& clouds_in_camera,
    const CameraMountParams& configured, const core::FloorPlaneParams& params) {
  MountCalibration c = calibrateMount(clouds_in_camera, configured, params);
  if (!c.ok()) {
    throw std::runtime_error(c.summary() +
                             "; the camera mount is unknown, not navigating (put the robot on "
                             "a level floor with the floor in view, or give the mount: --mount FILE.ini)");
  }
  return c;
}

std::string mountIniSection(const CameraMountParams& mount, const std::string& comment) {
  std::ostringstream os;
  os.precision(6);
  if (!comment.empty()) os << "; " << comment << "\n";
  os << "[CameraMountParams]\n"
     << "forward_m = " << mount.forward_m << "\n"
     << "left_m = " << mount.left_m << "\n"
     << "height_m = " << mount.height_m << "\n"
     << "pitch_deg = " << mount.pitch_rad * core::kRadToDeg << "\n"
     << "roll_deg = " << mount.roll_rad * core::kRadToDeg << "\n"
     << "image_downscale = " << mount.image_downscale << "\n";
  return os.str();
}

}  // namespace upd::sim
