#include "upd/mrpt_bridge/upd_observer.h"

#include "mrpt_util.h"
#include "upd/core/stopwatch.h"
#include "upd/mrpt_bridge/ini_params.h"
#include "upd/mrpt_bridge/pose_source.h"
#include "upd/mrpt_bridge/robot_config.h"

#include <mrpt/obs/CObservation.h>
#include <mrpt/poses/CPose3D.h>

#include <stdexcept>

namespace upd::mrpt_bridge {

void ObserverParams::validate() const {
  pipeline.validate();
  const Eigen::Vector3f up = pipeline.unitUp();
  core::requireParam(up.isApprox(Eigen::Vector3f::UnitZ(), 1e-6f), "ObserverParams", "pipeline.up",
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

namespace {

core::FrameScorerParams scorerParams(const ObserverParams& params) {
  params.validate();
  core::FrameScorerParams scorer;
  scorer.pipeline = params.pipeline;
  return scorer;
}

}  // namespace

UpdObserver::UpdObserver(const ObserverParams& params)
    : params_(params), scorer_(scorerParams(params)) {}

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
  const core::Stopwatch total;
  toCloud(obs, params_.source, result.cloud);
  const double convert_ms = total.elapsedMs();
  observeCloud(result.cloud, pose_world_robot, result);
  result.convert_ms = convert_ms;
  result.total_ms = total.elapsedMs();
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
  const core::Stopwatch total;
  result.source_class = cloud.source_class;
  result.skipped_reason = cloud.skipped_reason;
  result.pose_world_robot = pose_world_robot;
  result.pose_world_sensor = composeSensorPose(pose_world_robot, cloud.sensor_pose_on_robot);
  result.organized_input = false;
  result.points_input = 0;
  result.convert_ms = 0;
  if (!cloud.ok()) {
    result.scored = core::ScoredFrame{};
    result.total_ms = total.elapsedMs();
    return;
  }
  result.organized_input = cloud.organized();
  result.points_input = cloud.cloud_in_robot.countFinite();
  scorer_.score(cloud.cloud_in_robot, pose_world_robot, result.scored);
  result.total_ms = total.elapsedMs();
}

}  // namespace upd::mrpt_bridge
