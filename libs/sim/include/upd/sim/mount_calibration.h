// Calibrating the camera mount on the robot from the floor it sees: the first frames of a
// static camera (clouds in its optical frame) -> the floor plane (core/floor_plane.h) -> the
// [CameraMountParams] it implies (height_m, pitch_rad, roll_rad measured; forward_m, left_m and
// image_downscale kept from the configured mount, which the floor cannot tell). Used by
// `upd calibrate-mount` and `upd live --auto-mount`.
#pragma once

#include "upd/core/floor_plane.h"
#include "upd/core/point_cloud.h"
#include "upd/sim/robot.h"

#include <string>
#include <vector>

namespace upd::sim {

struct MountCalibration {
  core::FloorPlane floor;    ///< the plane found (floor.found), its residual and inlier share
  CameraMountParams mount;   ///< the calibrated mount (the configured one when !ok())
  std::size_t frames = 0;    ///< clouds used

  bool ok() const { return floor.found; }
  /// One line: "floor found in 5 frames: height 0.512 m, pitch 21.8 deg, roll -0.3 deg,
  /// residual 0.008 m, 41.2 % of the points on the plane", or why no floor was found.
  std::string summary() const;
};

/// The floor in clouds_in_camera and the mount it implies. The configured mount gives the
/// prior up direction (its pitch and roll) and the fields the floor does not measure. Never
/// throws when there is no floor (ok() is false); throws std::invalid_argument for bad params.
MountCalibration calibrateMount(const std::vector<const core::PointCloud*>& clouds_in_camera,
                                const CameraMountParams& configured,
                                const core::FloorPlaneParams& params = {});

/// The same, or std::runtime_error("no floor found in N frames: <why>; ... not navigating ...")
/// naming what to do: a run that needs the mount must not start without it.
MountCalibration requireCalibratedMount(
    const std::vector<const core::PointCloud*>& clouds_in_camera,
    const CameraMountParams& configured, const core::FloorPlaneParams& params = {});

/// The [CameraMountParams] ini section of mount (every key, degrees in the _deg keys), with
/// a comment line holding the calibration's summary when given.
std::string mountIniSection(const CameraMountParams& mount, const std::string& comment = {});

}  // namespace upd::sim
