#include "depth_input.h"

#include "calibrate_mount.h"
#include "cli.h"

#include "upd/io/cloud_io.h"
#include "upd/sim/robot.h"

#include <filesystem>
#include <stdexcept>

namespace upd::app {

core::DepthImage depthImageOf(const std::string& png, const mrpt_bridge::DepthCalibration& calib,
                              double metres_per_unit) {
  core::DepthImage depth = mrpt_bridge::readDepthPng(png, metres_per_unit);
  if (depth.width != calib.K.width || depth.height != calib.K.height) {
    throw std::runtime_error("depth image " + png + ": " + std::to_string(depth.width) + " x " +
                             std::to_string(depth.height) + " pixels, the calibration says " +
                             std::to_string(calib.K.width) + " x " +
                             std::to_string(calib.K.height));
  }
  return depth;
}

AnalyzeInput readAnalyzeInput(const std::string& input, const std::optional<std::string>& intrinsics_yaml,
                              double metres_per_unit, const std::optional<std::string>& mount_ini) {
  AnalyzeInput in;
  std::optional<Eigen::Isometry3d> camera_on_robot;
  if (std::filesystem::path(input).extension() == ".png") {
    if (!intrinsics_yaml) throw UsageError("a depth PNG needs --intrinsics CALIB.yaml");
    const auto calib = mrpt_bridge::loadDepthCalibration(*intrinsics_yaml);
    in.cloud = core::depthToCloud(depthImageOf(input, calib, metres_per_unit), calib.K);
    in.frame = "camera";
    camera_on_robot = calib.camera_on_robot;
    if (camera_on_robot) in.frame = "robot (local_transform)";
  } else {
    if (intrinsics_yaml) throw UsageError("--intrinsics is for a depth PNG INPUT");
    in.cloud = io::readCloud(input);
    in.frame = "file";
  }
  if (mount_ini) {
    sim::CameraMountParams mount;
    loadMountFile(*mount_ini, mount);
    camera_on_robot = sim::cameraOnRobot(mount);
    in.frame = "robot (--mount)";
  }
  if (camera_on_robot) {
    in.cloud = core::transformCloud(in.cloud, *camera_on_robot);
    in.up = Eigen::Vector3f::UnitZ();
  } else if (in.frame == "camera") {
    in.up = Eigen::Vector3f(0, -1, 0);
  }
  return in;
}

}  // namespace upd::app
