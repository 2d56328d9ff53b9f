#include "upd/core/pipeline.h"

#include "upd/core/fast_normals.h"
#include "upd/core/fast_upd.h"
#include "upd/core/kdtree.h"
#include "upd/core/stopwatch.h"

#include <cmath>

namespace upd::core {

void PipelineParams::validate() const {
  requireParam(up.allFinite() && up.norm() > 1e-6f, "PipelineParams", "up", up,
               "must be a non-zero finite vector");
  preprocess.validate();
  normals.validate();
  upd.validate();
  classify.validate();
  requireParam(upd.method != UpdMethod::Fast || normals.knn == 0, "UpdParams", "method", "fast",
               "the fast path needs radius neighbourhoods: NormalParams.knn must be 0");
}

UpdMethod resolveMethod(const PipelineParams& params) {
  switch (params.upd.method) {
    case UpdMethod::Exact: return UpdMethod::Exact;
    case UpdMethod::Fast: return UpdMethod::Fast;
    case UpdMethod::Auto: break;
  }
  return params.upd.knn == 0 && params.normals.knn == 0 ? UpdMethod::Fast : UpdMethod::Exact;
}

namespace {
/// The time since the last lap (or the start) [ms]; the next lap starts now.
double lapMs(Stopwatch& lap) {
  const double ms = lap.elapsedMs();
  lap.restart();
  return ms;
}
}  // namespace

PipelineResult runPipeline(const PointCloud& input, const PipelineParams& params) {
  PipelineResult res;
  runPipeline(input, params, res);
  return res;
}

void runPipeline(const PointCloud& input, const PipelineParams& params, PipelineResult& res) {
  params.validate();
  const Eigen::Vector3f up = params.unitUp();
  res.timings = StageTimings{};
  Stopwatch total, lap;
  preprocess(input, params.preprocess, res.cloud, &res.preprocess_stats);
  res.timings.preprocess_ms = lapMs(lap);
  res.method = resolveMethod(params);
  if (res.method == UpdMethod::Fast) {
    // No index to build: the normals and the UPD bin the points themselves.
    res.organized_normals = organizedNormalsApply(res.cloud, params.normals);
    if (res.organized_normals) {
      computeNormalsOrganized(res.cloud, params.normals, up, res.normals);
    } else {
      computeNormalsGrid(res.cloud, params.normals, up, res.normals);
    }
    res.timings.normals_ms = lapMs(lap);
    FastUpdStats stats;
    computeUpdFast(res.cloud, res.normals, params.upd, res.upd, &stats, params.classify.zeta_min);
    res.exact_band_points = stats.exact_points;
    res.fast_cells_per_radius = stats.cells_per_radius;
    res.timings.upd_ms = lapMs(lap);
  } else {
    res.organized_normals = false;
    res.exact_band_points = 0;
    res.fast_cells_per_radius = 0;
    const KdTree tree(res.cloud);
    res.timings.index_ms = lapMs(lap);
    res.normals = computeNormals(res.cloud, tree, params.normals, up);
    res.timings.normals_ms = lapMs(lap);
    res.upd = computeUpd(res.cloud, tree, res.normals, params.upd);
    res.timings.upd_ms = lapMs(lap);
  }
  classify(res.upd, up, params.classify, res.classes);
  if (params.labeler) applyPointLabeler(*params.labeler, res.cloud, res.normals, up, res.classes);
  res.timings.classify_ms = lapMs(lap);
  res.timings.total_ms = total.elapsedMs();
}

}  // namespace upd::core
