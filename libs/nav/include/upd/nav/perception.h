// One depth frame to traversability evidence, with the obstacle detector selectable: the UPD
// (the paper's method) or the roughness-index baseline (paper section 5), which reads a smooth
// 20 deg ramp as an obstacle.
//
// The cloud must be in a gravity-aligned frame with z up (the world frame of the navigation
// loop), with its sensor origin set: range cut-off and normal orientation use it. Both
// detectors run the same pre-processing (PipelineParams::preprocess); the roughness index uses
// BaselineParams (its radius is the UPD's d_m by default, as in the paper's comparison).
#pragma once

#include "upd/core/baselines.h"
#include "upd/core/pipeline.h"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace upd::nav {

enum class ObstacleDetector { Upd, Roughness };
const char* toString(ObstacleDetector d);
/// "upd" or "roughness"; throws std::invalid_argument naming the valid values otherwise.
ObstacleDetector parseObstacleDetector(const std::string& name);

/// A scored frame in the world frame.
struct FrameEvidence {
  PointCloud cloud_world;  ///< the pre-processed points that were scored
  Classification classes;  ///< one label (and cost, slope) per point
  UpdResult upd;           ///< the UPD (zeta, ...) per point; empty for the roughness index
  std::vector<Eigen::Vector2d> obstacles_world;  ///< xy of the NonTraversable points
  double score_ms = 0.0;                         ///< wall time of the scoring
};

/// Scores cloud_world (z up) with the chosen detector. params.up is ignored: the frame is z up.
FrameEvidence scoreFrame(const PointCloud& cloud_world, ObstacleDetector detector,
                         const PipelineParams& params, const BaselineParams& baseline);

}  // namespace upd::nav
