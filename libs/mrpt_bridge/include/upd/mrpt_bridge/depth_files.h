// Depth images on disk, the layout of most RGB-D datasets (TUM RGB-D, RTAB-Map, ETH3D): a
// 16-bit single-channel PNG of depth in fixed units (millimetres for RTAB-Map and ETH3D, 1/5000
// m for TUM), and the camera's intrinsics in a calibration YAML: OpenCV's (RTAB-Map's
// `%YAML:1.0` files) or ROS's camera_info (`camera_matrix: {rows: 3, cols: 3, data: [...]}`).
// An RTAB-Map calibration may hold `local_transform`, the 3 x 4 [R|t] of the camera-optical
// frame in the robot frame (x forward, y left, z up); it is returned when present.
//
// Errors name the file and the field: a missing file, a PNG that is not 16-bit single channel,
// a size that does not match the calibration, a focal length that is not > 0.
#pragma once

#include "upd/core/camera.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>

namespace upd::mrpt_bridge {

struct DepthCalibration {
  core::CameraIntrinsics K;
  /// pose_robot_camera (camera-optical -> robot) from `local_transform`, when the file has one.
  std::optional<Eigen::Isometry3d> camera_on_robot;
  bool has_distortion = false;  ///< non-zero distortion coefficients (not applied: depth images
                                ///< of RGB-D datasets are undistorted or nearly so)
};

/// Reads an OpenCV or ROS calibration YAML (header comment). Throws std::runtime_error naming
/// the file and the field.
DepthCalibration loadDepthCalibration(const std::string& yaml_path);

/// The largest depth image readDepthPng reads: its side and its pixels (depth cameras give a
/// few thousand a side, a few million in all).
constexpr std::uint32_t kMaxDepthSide = 16384;
constexpr std::uint64_t kMaxDepthPixels = std::uint64_t{1} << 25;

/// Reads a 16-bit depth PNG: depth_m = value * metres_per_unit (0 stays 0: invalid). Throws
/// std::runtime_error naming the file when it is missing, unreadable, not a PNG (by its
/// signature), larger than kMaxDepthSide a side or kMaxDepthPixels by its header (before any
/// allocation), damaged, or not 16-bit single channel; std::invalid_argument for
/// metres_per_unit <= 0.
core::DepthImage readDepthPng(const std::string& png_path, double metres_per_unit = 0.001);

/// Writes depth_m as a 16-bit PNG in units of metres_per_unit (rounded; 0 and NaN -> 0, values
/// beyond 65535 units -> 0), through a temporary file and a rename.
void writeDepthPng(const std::string& png_path, const core::DepthImage& depth,
                   double metres_per_unit = 0.001);

/// The intrinsics TUM RGB-D publishes for its depth images ("freiburg1", "freiburg2",
/// "freiburg3"; "ros" = the ROS default 525 / 319.5 / 239.5 of the Kinect), 640 x 480. Throws
/// std::invalid_argument naming the choices for another name.
core::CameraIntrinsics tumIntrinsics(const std::string& name);

}  // namespace upd::mrpt_bridge
