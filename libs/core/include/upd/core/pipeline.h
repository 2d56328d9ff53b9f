// The whole UPD chain on one cloud: pre-processing, normals, UPD, classification.
//
// This is what `upd analyze` runs and what the MRPT UPD observer calls per frame. Each stage is
// timed (file I/O is not part of it).
//
// UpdParams::method picks how normals and the UPD are computed; pre-processing runs as
// configured either way. The rule (resolveMethod):
//  - exact (1): k-d tree neighbourhoods, computeNormals and computeUpd, brute-force equal;
//  - fast (2): after pre-processing, an organized cloud (the input was organized and neither
//    voxel down-sampling nor outlier removal ran, so the image layout survived) with uniform
//    normal weights gets window-scan normals (computeNormalsOrganized), any other cloud gets
//    the exact neighbourhoods from a hash grid (computeNormalsGrid); then the UPD by the
//    voxel-moment lattice (computeUpdFast), whose cost per point does not grow with d_m.
//    Needs radius neighbourhoods (NormalParams::knn = UpdParams::knn = 0);
//  - auto (0, the default): fast when knn = 0 for both normals and UPD, else exact.
// For a depth camera at sensor rate: keep the cloud organized (range cut-off only) and let the
// fast path score every pixel. fast_upd.h and docs/PERFORMANCE.md state how far fast is from
// exact.
#pragma once

#include "upd/core/classify.h"
#include "upd/core/normals.h"
#include "upd/core/point_labeler.h"
#include "upd/core/preprocess.h"
#include "upd/core/upd.h"

namespace upd::core {

struct PipelineParams {
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< gravity-up in the cloud frame (any length)
  PreprocessParams preprocess;
  NormalParams normals;
  UpdParams upd;
  ClassifyParams classify;
  /// A learned classifier (`[ClassifyParams] classifier = FILE`, point_labeler.h): when set,
  /// it labels the points instead of the threshold rule.
  std::shared_ptr<const PointLabeler> labeler;

  /// Validates every part; throws std::invalid_argument naming the field and value.
  void validate() const;
  Eigen::Vector3f unitUp() const { return up.normalized(); }
};

struct StageTimings {
  double preprocess_ms = 0, index_ms = 0, normals_ms = 0, upd_ms = 0, classify_ms = 0,
         total_ms = 0;
};

/// The method runPipeline uses with these parameters (Exact or Fast, never Auto): the rule in
/// the header comment.
UpdMethod resolveMethod(const PipelineParams& params);

struct PipelineResult {
  PointCloud cloud;  ///< the pre-processed cloud that was scored
  Normals normals;
  UpdResult upd;
  Classification classes;
  PreprocessStats preprocess_stats;
  StageTimings timings;
  UpdMethod method = UpdMethod::Exact;  ///< exact or fast, as resolveMethod chose
  bool organized_normals = false;        ///< fast path: normals from image-window scans
  /// Fast path: the points whose zeta lay within UpdParams::fast_exact_band of the classifier's
  /// zeta_min and were summed exactly (0 with the band off).
  std::size_t exact_band_points = 0;
  /// Fast path: the lattice's cells per d_m (UpdParams::fast_cells_per_radius, or finer under
  /// fast_cells_per_point); 0 on the exact path.
  int fast_cells_per_radius = 0;
};

/// Runs the chain; throws std::invalid_argument for bad parameters. An empty input (or one
/// that pre-processing empties) gives an empty result, not an error.
PipelineResult runPipeline(const PointCloud& input, const PipelineParams& params);

/// The same into res, whose buffers are reused: a frame loop that keeps one PipelineResult
/// allocates nothing once warm (with the fast path and no pre-processing filter).
void runPipeline(const PointCloud& input, const PipelineParams& params, PipelineResult& res);

}  // namespace upd::core
