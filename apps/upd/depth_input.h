// Depth images and camera mounts as inputs of the `upd` commands: a 16-bit depth PNG with its
// calibration YAML becomes an organized cloud (upd/mrpt_bridge/depth_files.h), and a cloud in
// the camera-optical frame is moved to the robot frame by a mount (--mount FILE.ini) or by the
// calibration's own local_transform, so that up is +z and the floor can be scored as ground.
#pragma once

#include "upd/core/camera.h"
#include "upd/core/point_cloud.h"
#include "upd/mrpt_bridge/depth_files.h"

#include <Eigen/Core>

#include <optional>
#include <string>

namespace upd::app {

/// readDepthPng, checked against the calibration's image size (an error names both).
core::DepthImage depthImageOf(const std::string& png, const mrpt_bridge::DepthCalibration& calib,
                              double metres_per_unit);

/// What `upd analyze` scores.
struct AnalyzeInput {
  core::PointCloud cloud;
  /// Gravity-up in the cloud's frame, when the input fixes it (robot frame: +z; a camera frame
  /// without a mount: a level camera's -y); empty: the command line's or the config's.
  std::optional<Eigen::Vector3f> up;
  std::string frame;  ///< "robot (--mount)", "robot (local_transform)", "camera", "file"
};

/// INPUT as `upd analyze` reads it: a .png needs intrinsics_yaml (else a UsageError); another
/// file is read by io::readCloud. With mount_ini the cloud is taken as camera-optical and moved
/// to the robot frame by the mount.
AnalyzeInput readAnalyzeInput(const std::string& input, const std::optional<std::string>& intrinsics_yaml,
                              double metres_per_unit, const std::optional<std::string>& mount_ini);

}  // namespace upd::app
