#include "upd/mrpt/upd_observer.h"

#include "mrpt_util.h"
#include "upd/mrpt/ini_params.h"
#include "upd/mrpt/pose_source.h"

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <chrono>
#include <stdexcept>

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

namespace {
// [PipelineParams] holds only `up` (the other parts have their own sections).
struct UpKey {
  Eigen::Vector3f& up;
  void validate() const {}
  template <class V>
  void visit(V& v) {
    v("up", up, "gravity-up direction x,y,z in the scored frame (robot frame: 0,0,1)");
  }
};
}  // namespace

void loadObserverParams(IniReader& ini, ObserverParams& params) {
  UpKey up{params.pipeline.up};
  ini.read("PipelineParams", up);
  ini.read("PreprocessParams", params.pipeline.preprocess);
  ini.read("NormalParams", params.pipeline.normals);
  ini.read("UpdParams", params.pipeline.upd);
  ini.read("ClassifyParams", params.pipeline.classify);
  ini.read("SourceParams", params.source);
  ini.read("StereoMatchParams", params.source.stereo);
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
  const auto start = std::chrono::steady_clock::now();
  const ObservationCloud cloud = toCloud(obs, params_.source);
  const double convert_ms = detail::elapsedMs(start);
  ObserverResult result = observeCloud(cloud, pose_world_robot);
  result.timings.convert_ms = convert_ms;
  result.timings.total_ms = detail::elapsedMs(start);
  return result;
}

ObserverResult UpdObserver::observeCloud(const ObservationCloud& cloud,
                                         const Eigen::Isometry3d& pose_world_robot) const {
  const auto start = std::chrono::steady_clock::now();
  ObserverResult result;
  result.source_class = cloud.source_class;
  result.skipped_reason = cloud.skipped_reason;
  result.pose_world_robot = pose_world_robot;
  result.pose_world_sensor = composeSensorPose(pose_world_robot, cloud.sensor_pose_on_robot);
  if (!cloud.ok()) {
    result.timings.total_ms = detail::elapsedMs(start);
    return result;
  }
  result.organized_input = cloud.organized();
  result.points_input = cloud.cloud_in_robot.countFinite();

  PipelineParams pipeline = params_.pipeline;
  // Gravity (world +z) seen from the robot: +z for planar poses.
  pipeline.up = (pose_world_robot.linear().transpose() * Eigen::Vector3d::UnitZ()).cast<float>();
  PipelineResult scored = runPipeline(cloud.cloud_in_robot, pipeline);
  result.timings.pipeline = scored.timings;

  const auto to_world_start = std::chrono::steady_clock::now();
  result.points_in_world = transformCloud(scored.cloud, pose_world_robot);
  const Eigen::Matrix3f rotation = pose_world_robot.linear().cast<float>();
  const auto rotate = [&rotation](std::vector<float>& x, std::vector<float>& y,
                                  std::vector<float>& z) {
    for (std::size_t i = 0; i < x.size(); ++i) {
      const Eigen::Vector3f v = rotation * Eigen::Vector3f(x[i], y[i], z[i]);  // NaN stays NaN
      x[i] = v.x();
      y[i] = v.y();
      z[i] = v.z();
    }
  };
  result.normals_in_world = std::move(scored.normals);
  rotate(result.normals_in_world.nx, result.normals_in_world.ny, result.normals_in_world.nz);
  result.upd_in_world = std::move(scored.upd);
  rotate(result.upd_in_world.rx, result.upd_in_world.ry, result.upd_in_world.rz);
  result.classes = std::move(scored.classes);
  result.preprocess_stats = scored.preprocess_stats;
  result.timings.to_world_ms = detail::elapsedMs(to_world_start);
  result.timings.total_ms = detail::elapsedMs(start);
  return result;
}

}  // namespace upd::mrptbridge
