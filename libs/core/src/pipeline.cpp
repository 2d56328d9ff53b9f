#include "upd/core/pipeline.h"

#include "upd/core/fast_normals.h"
#include "upd/core/fast_upd.h"
#include "upd/core/kdtree.h"

#include <chrono>
#include <cmath>

namespace upd {

void PipelineParams::validate() const {
  requireParam(up.allFinite() && up.norm() > 1e-6f, "PipelineParams", "up", up,
               "must be a non-zero finite vector");
  preprocess.validate();
  normals.validate();
  upd.validate();
  classify.validate();
  requireParam(upd.method != static_cast<int>(UpdMethod::Fast) || normals.knn == 0, "UpdParams",
               "method", upd.method,
               "the fast path (2) needs radius neighbourhoods: NormalParams.knn must be 0");
}

UpdMethod resolveMethod(const PipelineParams& params) {
  switch (static_cast<UpdMethod>(params.upd.method)) {
    case UpdMethod::Exact: return UpdMethod::Exact;
    case UpdMethod::Fast: return UpdMethod::Fast;
    case UpdMethod::Auto: break;
  }
  return params.upd.knn == 0 && params.normals.knn == 0 ? UpdMethod::Fast : UpdMethod::Exact;
}

namespace {
class Stopwatch {
 public:
  double lapMs() {
    const auto now = std::chrono::steady_clock::now();
    const double ms = std::chrono::duration<double, std::milli>(now - last_).count();
    last_ = now;
    return ms;
  }

 private:
  std::chrono::steady_clock::time_point last_ = std::chrono::steady_clock::now();
};
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
  res.timings.preprocess_ms = lap.lapMs();
  res.method = resolveMethod(params);
  if (res.method == UpdMethod::Fast) {
    // No index to build: the normals and the UPD bin the points themselves.
    res.organized_normals = organizedNormalsApply(res.cloud, params.normals);
    if (res.organized_normals) {
      computeNormalsOrganized(res.cloud, params.normals, up, res.normals);
    } else {
      res.normals = computeNormalsGrid(res.cloud, params.normals, up);
    }
    res.timings.normals_ms = lap.lapMs();
    FastUpdStats stats;
    computeUpdFast(res.cloud, res.normals, params.upd, res.upd, &stats, params.classify.zeta_min);
    res.exact_band_points = stats.exact_points;
    res.fast_cells_per_radius = stats.cells_per_radius;
    res.timings.upd_ms = lap.lapMs();
  } else {
    res.organized_normals = false;
    res.exact_band_points = 0;
    res.fast_cells_per_radius = 0;
    const KdTree tree(res.cloud);
    res.timings.index_ms = lap.lapMs();
    res.normals = computeNormals(res.cloud, tree, params.normals, up);
    res.timings.normals_ms = lap.lapMs();
    res.upd = computeUpd(res.cloud, tree, res.normals, params.upd);
    res.timings.upd_ms = lap.lapMs();
  }
  classify(res.upd, up, params.classify, res.classes);
  res.timings.classify_ms = lap.lapMs();
  res.timings.total_ms = total.lapMs();
}

}  // namespace upd
