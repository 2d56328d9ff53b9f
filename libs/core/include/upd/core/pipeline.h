// The whole UPD chain on one cloud: pre-processing, normals, UPD, classification.
//
// This is what `upd analyze` runs and what the MRPT UPD observer calls per frame. Each stage is
// timed (file I/O is not part of it).
#pragma once

#include "upd/core/classify.h"
#include "upd/core/normals.h"
#include "upd/core/preprocess.h"
#include "upd/core/upd.h"

namespace upd {

struct PipelineParams {
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< gravity-up in the cloud frame (any length)
  PreprocessParams preprocess;
  NormalParams normals;
  UpdParams upd;
  ClassifyParams classify;

  /// Validates every part; throws std::invalid_argument naming the field and value.
  void validate() const;
  Eigen::Vector3f unitUp() const { return up.normalized(); }
};

struct StageTimings {
  double preprocess_ms = 0, index_ms = 0, normals_ms = 0, upd_ms = 0, classify_ms = 0,
         total_ms = 0;
};

struct PipelineResult {
  PointCloud cloud;  ///< the pre-processed cloud that was scored
  Normals normals;
  UpdResult upd;
  Classification classes;
  PreprocessStats preprocess_stats;
  StageTimings timings;
};

/// Runs the chain; throws std::invalid_argument for bad parameters. An empty input (or one
/// that pre-processing empties) gives an empty result, not an error.
PipelineResult runPipeline(const PointCloud& input, const PipelineParams& params);

}  // namespace upd
