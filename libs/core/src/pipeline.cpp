#include "upd/core/pipeline.h"

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
  params.validate();
  const Eigen::Vector3f up = params.unitUp();
  PipelineResult res;
  Stopwatch total, lap;
  res.cloud = preprocess(input, params.preprocess, &res.preprocess_stats);
  res.timings.preprocess_ms = lap.lapMs();
  const KdTree tree(res.cloud);
  res.timings.index_ms = lap.lapMs();
  res.normals = computeNormals(res.cloud, tree, params.normals, up);
  res.timings.normals_ms = lap.lapMs();
  res.upd = computeUpd(res.cloud, tree, res.normals, params.upd);
  res.timings.upd_ms = lap.lapMs();
  res.classes = classify(res.upd, up, params.classify);
  res.timings.classify_ms = lap.lapMs();
  res.timings.total_ms = total.lapMs();
  return res;
}

}  // namespace upd
