#include "upd/core/frame_scorer.h"

#include "upd/core/kdtree.h"
#include "upd/core/params.h"
#include "upd/core/preprocess.h"
#include "upd/core/stopwatch.h"

#include <limits>
#include <stdexcept>

namespace upd::core {

const char* toString(ObstacleDetector detector) {
  return detector == ObstacleDetector::Upd ? "upd" : "roughness";
}

ObstacleDetector parseObstacleDetector(const std::string& name) {
  if (name == "upd") return ObstacleDetector::Upd;
  if (name == "roughness") return ObstacleDetector::Roughness;
  throw std::invalid_argument("obstacle detector '" + name + "': expected upd or roughness");
}

void FrameScorerParams::validate() const {
  pipeline.validate();
  requireParam(pipeline.unitUp().isApprox(Eigen::Vector3f::UnitZ(), 1e-6f), "FrameScorerParams",
               "pipeline.up", pipeline.up,
               "must be 0,0,1: the world frame is z up and the scorer takes gravity in the "
               "cloud frame from the cloud's pose");
  requireParam(detector == ObstacleDetector::Upd || detector == ObstacleDetector::Roughness,
               "FrameScorerParams", "detector", static_cast<int>(detector),
               "must be upd or roughness");
  baseline.validate();
}

namespace {

// The roughness index as a Classification, so the map fuses it like the UPD's labels: cost 0
// (traversable) or 1 (non-traversable), slope from the inclination index.
void roughnessClasses(const BaselineResult& b, Classification& c) {
  const std::size_t n = b.roughness_label.size();
  c.label = b.roughness_label;
  c.cost.assign(n, std::numeric_limits<float>::quiet_NaN());
  c.slope_rad = b.inclination_rad;
  c.traversable = c.non_traversable = c.unknown = 0;
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
}

// The roughness index in the cloud frame, into res (no normals, no UPD). Without voxel or
// outlier filtering the cloud keeps its NaN pixels; the index needs only the valid ones.
void scoreRoughness(const PointCloud& cloud, const FrameScorerParams& params,
                    const Eigen::Vector3f& up, PipelineResult& res) {
  const Stopwatch total;
  Stopwatch stage;
  res.preprocess_stats = PreprocessStats{};
  res.cloud = dropNonFinite(preprocess(cloud, params.pipeline.preprocess, &res.preprocess_stats));
  res.timings = StageTimings{};
  res.timings.preprocess_ms = stage.elapsedMs();
  res.normals = Normals{};
  res.upd = UpdResult{};
  res.classes = Classification{};
  if (!res.cloud.empty()) {
    stage.restart();
    const KdTree tree(res.cloud);
    res.timings.index_ms = stage.elapsedMs();
    stage.restart();
    roughnessClasses(computeBaselines(res.cloud, tree, up, params.baseline), res.classes);
    res.timings.classify_ms = stage.elapsedMs();
  }
  res.timings.total_ms = total.elapsedMs();
}

// out = the cloud-frame results in scratch moved by pose. The buffers are swapped, not copied:
// scratch takes out's of the last frame, which the next frame's pipeline overwrites (it writes
// every element), and the points and vectors are moved in place (no copy of the colours, zeta,
// k, curvature and classes; a pass over each moved array instead of a read and a write of two).
void moveToWorld(PipelineResult& scratch, const Eigen::Isometry3d& pose, ScoredFrame& out) {
  std::swap(out.cloud_world, scratch.cloud);
  std::swap(out.normals_world, scratch.normals);
  std::swap(out.upd, scratch.upd);
  std::swap(out.classes, scratch.classes);  // labels, costs and slopes are the same in both frames
  out.preprocess_stats = scratch.preprocess_stats;
  if (pose.matrix() == Eigen::Matrix4d::Identity()) return;
  transformInPlace(out.cloud_world, pose);
  const Eigen::Matrix3f rotation = pose.linear().cast<float>();
  Normals& n = out.normals_world;
  rotateVectors(rotation, n.size(), n.nx.data(), n.ny.data(), n.nz.data());
  UpdResult& u = out.upd;
  rotateVectors(rotation, u.rx.size(), u.rx.data(), u.ry.data(), u.rz.data());
}

void collectObstacles(ScoredFrame& out) {
  out.obstacles_world.clear();
  const PointCloud& c = out.cloud_world;
  for (std::size_t i = 0; i < out.classes.label.size(); ++i) {
    if (out.classes.label[i] == Label::NonTraversable && c.isFinite(i)) {
      out.obstacles_world.emplace_back(c.x[i], c.y[i]);
    }
  }
}

}  // namespace

FrameScorer::FrameScorer(const FrameScorerParams& params) : params_(params) {
  params_.validate();
}

void FrameScorer::score(const PointCloud& cloud, const Eigen::Isometry3d& pose_world_cloud,
                        ScoredFrame& out) const {
  const Stopwatch total;
  // Gravity (world +z) seen from the cloud's frame: +z for planar poses.
  const Eigen::Vector3f up =
      (pose_world_cloud.linear().transpose() * Eigen::Vector3d::UnitZ()).cast<float>();
  if (params_.detector == ObstacleDetector::Upd) {
    PipelineParams pipeline = params_.pipeline;
    pipeline.up = up;
    runPipeline(cloud, pipeline, out.scratch);
  } else {
    scoreRoughness(cloud, params_, up.normalized(), out.scratch);
  }
  const Stopwatch to_world;
  moveToWorld(out.scratch, pose_world_cloud, out);
  if (params_.obstacles_xy) {
    collectObstacles(out);
  } else {
    out.obstacles_world.clear();
  }
  out.timings.stages = out.scratch.timings;
  out.timings.to_world_ms = to_world.elapsedMs();
  out.timings.total_ms = total.elapsedMs();
}

ScoredFrame FrameScorer::score(const PointCloud& cloud,
                               const Eigen::Isometry3d& pose_world_cloud) const {
  ScoredFrame out;
  score(cloud, pose_world_cloud, out);
  return out;
}

}  // namespace upd::core
