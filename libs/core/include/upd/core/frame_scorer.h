// The per-frame scorer: one point cloud in its own frame and the pose of that frame in the world
// in, scored points in the WORLD frame out. What playback (through the MRPT observer), `upd live`
// and `upd navigate` (through the navigation loop) run for every frame.
//
// The cloud is scored in its own frame (a robot or sensor frame keeps the voxel grid and the
// range cut-off tied to the sensor and the float coordinates small wherever the robot is; a
// world-frame cloud is passed with the identity pose), then the points, normals and UPD vectors
// r are moved to the world frame by pose_world_cloud. Gravity-up is the world's +z seen from the
// cloud's frame (R^T e_z), so slopes are measured against gravity for any pose.
//
// The obstacle detector is an option: the UPD (the paper's method: pre-processing, PCA normals,
// UPD eqs. 4-8, classification; upd::runPipeline) or the roughness-index baseline (paper
// section 5: the same pre-processing, then BaselineParams), which reads a smooth 20 deg ramp as
// an obstacle.
//
// The scorer holds only its parameters: score() is const and may run on several threads, each
// with its own ScoredFrame. Pass the same ScoredFrame every frame: its buffers and the scratch
// it keeps for the cloud-frame results trade places every frame (the results are moved to the
// world in place, not copied), so from the third frame on a frame of the size of the previous
// ones allocates no new storage for the results. The pre-processing reuses them too when the voxel
// grid is on (the outlier filter's search buffers are those of the scoring thread, kept from
// frame to frame); the outlier filter without the voxel grid still builds fresh clouds.
#pragma once

#include "upd/core/baselines.h"
#include "upd/core/pipeline.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace upd::core {

enum class ObstacleDetector { Upd, Roughness };
/// "upd" or "roughness".
const char* toString(ObstacleDetector detector);
/// "upd" or "roughness"; throws std::invalid_argument naming the valid values otherwise.
ObstacleDetector parseObstacleDetector(const std::string& name);

struct FrameScorerParams {
  /// The UPD chain; its pre-processing serves both detectors. pipeline.up must stay 0,0,1 (the
  /// world's gravity-up): the scorer takes gravity in the cloud frame from pose_world_cloud.
  PipelineParams pipeline;
  ObstacleDetector detector = ObstacleDetector::Upd;
  BaselineParams baseline;  ///< the roughness index (detector Roughness only)
  /// Also list the world xy of every NonTraversable point (ScoredFrame::obstacles_world), as
  /// the navigator's current-frame obstacles.
  bool obstacles_xy = false;

  /// Throws std::invalid_argument naming the field and value.
  void validate() const;
};

struct FrameScorerTimings {
  /// The detector's stages in the cloud frame (the roughness index fills preprocess_ms,
  /// index_ms and classify_ms).
  StageTimings stages;
  double to_world_ms = 0;  ///< moving the results to the world frame [ms]
  double total_ms = 0;     ///< the whole score() [ms]
};

/// One scored frame, world frame. Every per-point vector has one entry per scored point, in
/// the same order.
struct ScoredFrame {
  /// The scored (pre-processed) points [m]; sensor_origin = the sensor in the world.
  PointCloud cloud_world;
  Normals normals_world;  ///< unit normals; NaN where none; empty for the roughness index
  UpdResult upd;          ///< r in the world frame, zeta, k; empty for the roughness index
  /// Label, cost [0, 1] and slope against gravity [rad]: frame-free. The roughness index gives
  /// cost 0 or 1 and the inclination index as slope.
  Classification classes;
  /// xy [m] of the finite NonTraversable points (FrameScorerParams::obstacles_xy; else empty).
  std::vector<Eigen::Vector2d> obstacles_world;
  PreprocessStats preprocess_stats;
  FrameScorerTimings timings;

  std::size_t size() const { return cloud_world.size(); }

  /// Storage reused by the next score(): the cloud-frame results. Not part of the result.
  PipelineResult scratch;
};

class FrameScorer {
 public:
  /// Validates params (throws std::invalid_argument).
  explicit FrameScorer(const FrameScorerParams& params = FrameScorerParams());
  const FrameScorerParams& params() const { return params_; }

  /// Scores cloud (in its own frame, sensor origin set: range cut-off and normal orientation
  /// use it) and moves the results to the world by pose_world_cloud (p_world =
  /// pose_world_cloud * p_cloud). Every field of out is rewritten. An empty cloud (or one that
  /// pre-processing empties) gives an empty frame.
  void score(const PointCloud& cloud, const Eigen::Isometry3d& pose_world_cloud,
             ScoredFrame& out) const;
  ScoredFrame score(const PointCloud& cloud, const Eigen::Isometry3d& pose_world_cloud) const;

 private:
  FrameScorerParams params_;
};

}  // namespace upd::core
