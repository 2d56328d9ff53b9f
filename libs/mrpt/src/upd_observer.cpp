#include "upd/mrpt/upd_observer.h"

#include "mrpt_util.h"
#include "upd/mrpt/ini_params.h"
#include "upd/mrpt/pose_source.h"
#include "upd/mrpt/robot_config.h"

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <chrono>
#include <stdexcept>
#include <utility>

namespace upd::mrptbridge {

void ObserverParams::validate() const {
  pipeline.validate();
  const Eigen::Vector3f up = pipeline.unitUp();
  requireParam(up.isApprox(Eigen::Vector3f::UnitZ(), 1e-6f), "ObserverParams", "pipeline.up",
               pipeline.up,
               "must be 0,0,1: the observer scores clouds in the robot frame (z up) and takes "
               "gravity from the robot pose");
  source.validate();
}

void loadObserverParams(IniReader& ini, ObserverParams& params) {
  RobotConfigParts parts;
  parts.pipeline = &params.pipeline;
  parts.source = &params.source;
  readRobotConfig(ini, parts);
  try {
    params.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("config file " + ini.path() + ": " + e.what());
  }
}

void loadObserverParams(const std::string& ini_path, ObserverParams& params) {
  IniReader ini(ini_path);
  loadObserverParams(ini, params);
  ini.checkAllKeysKnown();
}

UpdObserver::UpdObserver(const ObserverParams& params) : params_(params) { params_.validate(); }

ObserverResult UpdObserver::observe(const mrpt::obs::CObservation& obs,
                                    const mrpt::poses::CPose3D& pose_world_robot) const {
  return observe(obs, toIsometry(pose_world_robot));
}

ObserverResult UpdObserver::observe(const mrpt::obs::CObservation& obs,
                                    const Eigen::Isometry3d& pose_world_robot) const {
  ObserverResult result;
  observe(obs, pose_world_robot, result);
  return result;
}

void UpdObserver::observe(const mrpt::obs::CObservation& obs,
                          const Eigen::Isometry3d& pose_world_robot, ObserverResult& result) const {
  const auto start = std::chrono::steady_clock::now();
  // The calling thread's converted cloud, kept for its next frame.
  static thread_local ObservationCloud cloud;
  toCloud(obs, params_.source, cloud);
  const double convert_ms = detail::elapsedMs(start);
  observeCloud(cloud, pose_world_robot, result);
  result.timings.convert_ms = convert_ms;
  result.timings.total_ms = detail::elapsedMs(start);
}

ObserverResult UpdObserver::observeCloud(const ObservationCloud& cloud,
                                         const Eigen::Isometry3d& pose_world_robot) const {
  ObserverResult result;
  observeCloud(cloud, pose_world_robot, result);
  return result;
}

void UpdObserver::observeCloud(const ObservationCloud& cloud,
                               const Eigen::Isometry3d& pose_world_robot,
                               ObserverResult& result) const {
  const auto start = std::chrono::steady_clock::now();
  result.source_class = cloud.source_class;
  result.skipped_reason = cloud.skipped_reason;
  result.pose_world_robot = pose_world_robot;
  result.pose_world_sensor = composeSensorPose(pose_world_robot, cloud.sensor_pose_on_robot);
  result.organized_input = false;
  result.points_input = 0;
  result.timings = ObserverTimings{};
  if (!cloud.ok()) {
    result.points_in_world = PointCloud{};
    result.normals_in_world = Normals{};
    result.upd_in_world = UpdResult{};
    result.classes = Classification{};
    result.preprocess_stats = PreprocessStats{};
    result.timings.total_ms = detail::elapsedMs(start);
    return;
  }
  result.organized_input = cloud.organized();
  result.points_input = cloud.cloud_in_robot.countFinite();

  PipelineParams pipeline = params_.pipeline;
  // Gravity (world +z) seen from the robot: +z for planar poses.
  pipeline.up = (pose_world_robot.linear().transpose() * Eigen::Vector3d::UnitZ()).cast<float>();
  // The robot-frame results: the calling thread's, kept for its next frame.
  static thread_local PipelineResult scored;
  runPipeline(cloud.cloud_in_robot, pipeline, scored);
  result.timings.pipeline = scored.timings;

  const auto to_world_start = std::chrono::steady_clock::now();
  transformCloud(scored.cloud, pose_world_robot, result.points_in_world);
  const Eigen::Matrix3f rotation = pose_world_robot.linear().cast<float>();
  const std::size_t n = scored.cloud.size();
  Normals& normals = result.normals_in_world;
  normals.nx.resize(n), normals.ny.resize(n), normals.nz.resize(n);
  rotateVectors(rotation, n, scored.normals.nx.data(), scored.normals.ny.data(),
                scored.normals.nz.data(), normals.nx.data(), normals.ny.data(), normals.nz.data());
  normals.curvature = scored.normals.curvature;
  normals.invalid = scored.normals.invalid;
  UpdResult& upd = result.upd_in_world;
  upd.rx.resize(n), upd.ry.resize(n), upd.rz.resize(n);
  rotateVectors(rotation, n, scored.upd.rx.data(), scored.upd.ry.data(), scored.upd.rz.data(),
                upd.rx.data(), upd.ry.data(), upd.rz.data());
  upd.zeta = scored.upd.zeta;
  upd.k = scored.upd.k;
  upd.invalid = scored.upd.invalid;
  // Labels, costs and slopes are the same in both frames: the buffers change hands (the
  // scratch gets result's previous ones, of the same size, to fill next frame).
  std::swap(result.classes, scored.classes);
  result.preprocess_stats = scored.preprocess_stats;
  result.timings.to_world_ms = detail::elapsedMs(to_world_start);
  result.timings.total_ms = detail::elapsedMs(start);
}

}  // namespace upd::mrptbridge
