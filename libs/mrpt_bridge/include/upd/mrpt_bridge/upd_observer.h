// The UPD observer: one MRPT observation and the robot pose in, per-point UPD, traversability
// labels and costs in the WORLD frame out. The MRPT adapter of upd::FrameScorer.
//
// The observation becomes a cloud in the robot frame (observation_cloud.h) and the frame scorer
// (upd/core/frame_scorer.h) runs the whole UPD chain there (pre-processing, PCA normals, UPD
// eqs. 4-8, classification), then moves the scored points, their normals and UPD vectors r to
// the world frame by pose_world_robot. Scoring in the robot frame keeps the voxel grid and the
// range cut-off tied to the sensor and the float coordinates small wherever the robot is.
// Gravity-up for the slope is the world's +z expressed in the robot frame, which is the robot's
// +z for any planar pose (odometry); a robot tilted in 3D (a ground-truth pose) still measures
// slope against gravity.
//
// The observer holds only its parameters: observe() is const and may run on several threads,
// each with its own ObserverResult. In a frame loop, pass the same ObserverResult to
// observe(obs, pose, result) every frame: its buffers (the converted cloud and the scorer's
// storage included) are reused. Once warm, a frame with pre-processing off allocates nothing for
// the scores; the observation's conversion to a cloud and the voxel grid / outlier filter, when
// enabled, still build fresh clouds.
#pragma once

#include "upd/core/frame_scorer.h"
#include "upd/core/pipeline.h"
#include "upd/mrpt_bridge/observation_cloud.h"

#include <Eigen/Geometry>

#include <string>

namespace mrpt::obs {
class CObservation;
}
namespace mrpt::poses {
class CPose3D;
}

namespace upd::mrpt_bridge {

class IniReader;

struct ObserverParams {
  /// The UPD chain. pipeline.up must stay 0,0,1: clouds are scored in the robot frame (z up)
  /// and gravity comes from the robot pose.
  core::PipelineParams pipeline;
  SourceParams source;  ///< how observations become clouds

  /// Throws std::invalid_argument naming the field and value.
  void validate() const;
};

/// Reads [PipelineParams] (key `up`, must be 0,0,1), [PreprocessParams], [NormalParams],
/// [UpdParams], [ClassifyParams], [SourceParams] and [StereoMatchParams] from ini (absent
/// sections and keys keep their defaults) and validates. It does not call
/// ini.checkAllKeysKnown(): the file may hold other components' sections; the caller checks once
/// everything is read.
void loadObserverParams(IniReader& ini, ObserverParams& params);
/// The same from a file that holds only these sections (unknown sections or keys are errors).
void loadObserverParams(const std::string& ini_path, ObserverParams& params);

struct ObserverResult {
  std::string source_class;    ///< short MRPT class name of the observation
  std::string skipped_reason;  ///< non-empty: the observation gave no cloud, and why
  bool ok() const { return skipped_reason.empty(); }

  Eigen::Isometry3d pose_world_robot = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d pose_world_sensor = Eigen::Isometry3d::Identity();
  bool organized_input = false;  ///< the converted cloud kept an image layout
  std::size_t points_input = 0;  ///< finite points of the converted cloud

  /// The scored (pre-processed) points in the world frame, their normals, UPD (r in the world
  /// frame), labels, costs and slopes against gravity, and the scorer's stage timings; empty
  /// when skipped. cloud_world.sensor_origin = the sensor's position in the world.
  core::ScoredFrame scored;
  double convert_ms = 0;  ///< observation -> cloud in the robot frame [ms]
  double total_ms = 0;    ///< the whole observe() [ms]

  std::size_t size() const { return scored.size(); }

  /// Storage reused by the next observe(): the converted cloud. Not part of the result.
  ObservationCloud cloud;
};

class UpdObserver {
 public:
  /// Validates params (throws std::invalid_argument).
  explicit UpdObserver(const ObserverParams& params = ObserverParams());
  const ObserverParams& params() const { return params_; }
  const core::FrameScorer& scorer() const { return scorer_; }

  ObserverResult observe(const mrpt::obs::CObservation& obs,
                         const mrpt::poses::CPose3D& pose_world_robot) const;
  ObserverResult observe(const mrpt::obs::CObservation& obs,
                         const Eigen::Isometry3d& pose_world_robot) const;
  /// The same into result, reusing its buffers (every field is rewritten).
  void observe(const mrpt::obs::CObservation& obs, const Eigen::Isometry3d& pose_world_robot,
               ObserverResult& result) const;
  /// For clouds already in the robot frame (e.g. stereoToCloud moved by the camera pose);
  /// convert_ms is 0.
  ObserverResult observeCloud(const ObservationCloud& cloud,
                              const Eigen::Isometry3d& pose_world_robot) const;
  void observeCloud(const ObservationCloud& cloud, const Eigen::Isometry3d& pose_world_robot,
                    ObserverResult& result) const;

 private:
  ObserverParams params_;
  core::FrameScorer scorer_;
};

}  // namespace upd::mrpt_bridge
