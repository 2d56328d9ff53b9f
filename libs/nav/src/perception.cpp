#include "upd/nav/perception.h"

#include "upd/core/kdtree.h"
#include "upd/core/preprocess.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace upd::nav {

const char* toString(ObstacleDetector d) {
  return d == ObstacleDetector::Upd ? "upd" : "roughness";
}

ObstacleDetector parseObstacleDetector(const std::string& name) {
  if (name == "upd") return ObstacleDetector::Upd;
  if (name == "roughness") return ObstacleDetector::Roughness;
  throw std::invalid_argument("obstacle detector '" + name + "': expected upd or roughness");
}

namespace {

// The roughness index as a Classification, so the map fuses it like the UPD's labels: cost 0
// (traversable) or 1 (non-traversable), slope from the inclination index.
Classification roughnessClasses(const BaselineResult& b) {
  Classification c;
  const std::size_t n = b.roughness_label.size();
  c.label = b.roughness_label;
  c.cost.assign(n, std::numeric_limits<float>::quiet_NaN());
  c.slope_rad = b.inclination_rad;
  for (std::size_t i = 0; i < n; ++i) {
    switch (c.label[i]) {
      case Label::Traversable:
        c.cost[i] = 0.f;
        ++c.traversable;
        break;
      case Label::NonTraversable:
        c.cost[i] = 1.f;
        ++c.non_traversable;
        break;
      case Label::Unknown: ++c.unknown; break;
    }
  }
  return c;
}

}  // namespace

FrameEvidence scoreFrame(const PointCloud& cloud_world, ObstacleDetector detector,
                         const PipelineParams& params, const BaselineParams& baseline) {
  const auto t0 = std::chrono::steady_clock::now();
  PipelineParams p = params;
  p.up = Eigen::Vector3f::UnitZ();
  FrameEvidence ev;
  if (detector == ObstacleDetector::Upd) {
    PipelineResult r = runPipeline(cloud_world, p);
    ev.cloud_world = std::move(r.cloud);
    ev.classes = std::move(r.classes);
    ev.upd = std::move(r.upd);
  } else {
    p.validate();
    baseline.validate();
    // Without voxel or outlier filtering the cloud keeps its NaN pixels; the index needs only
    // the valid ones.
    ev.cloud_world = dropNonFinite(preprocess(cloud_world, p.preprocess));
    if (!ev.cloud_world.empty()) {
      const KdTree tree(ev.cloud_world);
      ev.classes = roughnessClasses(
          computeBaselines(ev.cloud_world, tree, Eigen::Vector3f::UnitZ(), baseline));
    }
  }
  for (std::size_t i = 0; i < ev.classes.label.size(); ++i) {
    if (ev.classes.label[i] == Label::NonTraversable && ev.cloud_world.isFinite(i)) {
      ev.obstacles_world.emplace_back(ev.cloud_world.x[i], ev.cloud_world.y[i]);
    }
  }
  ev.score_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return ev;
}

}  // namespace upd::nav
