// Scoring one labelled cloud for `upd evaluate` and `upd train`: the cloud is pre-processed
// and its normals computed as its config says (dune-kinect.ini, lidar.ini, or --config), the
// truth moves to the kept points (each takes the label of the nearest input point), then every
// score of upd/core/point_features.h is computed at each d_m (exact k-d tree sums) and the
// rules applied. Results of many clouds are pooled per group, per point and per map cell.
#pragma once

#include "evaluate_data.h"

#include "upd/core/binary_metrics.h"
#include "upd/core/pipeline.h"
#include "upd/core/point_features.h"
#include "upd/core/point_labeler.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace upd::app {

struct EvalSettings {
  std::vector<double> radii_m = {0.3, 0.5, 1.0};  ///< the d_m of the table
  double cell_m = 0.2;                             ///< map cells of the per-cell table [m]
  std::string config;  ///< a config for every cloud; "" = each cloud's shipped config
  std::shared_ptr<const core::PointLabeler> classifier;  ///< may be null
  core::FeatureParams features;  ///< the classifier's (or the defaults)
};

/// One cloud after processing: its points, truth, scores and the rules' labels.
struct ProcessedCloud {
  core::PointCloud cloud;
  std::vector<core::Label> truth;
  Eigen::Vector3f up;
  core::PipelineParams params;  ///< the config it was scored with
  core::PointScores scores;
  std::vector<float> features;  ///< row-major core::kFeatureCount per point
  std::vector<float> classifier;  ///< probability, when a classifier is set
};

ProcessedCloud processCloud(const LabelledCloud& in, const EvalSettings& settings);

/// One detector: a continuous score (higher = more likely non-traversable) and its rule.
struct Method {
  std::string name;
  double radius_m = 0;  ///< its d_m; 0 when it has none
  std::string rule;     ///< the rule, as text ("zeta < 0.95 or slope > 25 deg")
  std::vector<float> score;
  std::vector<core::Label> label;  ///< the rule's labels
};

/// Every detector on a processed cloud, in a fixed order.
std::vector<Method> methodsOf(const ProcessedCloud& pc, const EvalSettings& settings);

/// The results of one detector on a group.
struct MethodResult {
  std::string name, rule;
  double radius_m = 0;
  core::BinaryCounts counts;  ///< of the rule
  core::RocCurve roc;         ///< of the score
};

/// Pools the clouds of one group; per point and per map cell.
class GroupPool {
 public:
  explicit GroupPool(std::string group) : group_(std::move(group)) {}
  void add(const ProcessedCloud& pc, const EvalSettings& settings);
  const std::string& group() const { return group_; }
  std::size_t clouds() const { return clouds_; }
  std::size_t points() const { return point_truth_.size(); }
  std::size_t cells() const { return cell_truth_.size(); }
  std::vector<MethodResult> pointResults() const { return results(point_truth_, point_); }
  std::vector<MethodResult> cellResults() const { return results(cell_truth_, cell_); }

 private:
  static std::vector<MethodResult> results(const std::vector<core::Label>& truth,
                                           const std::vector<Method>& methods);
  std::string group_;
  std::size_t clouds_ = 0;
  std::vector<core::Label> point_truth_, cell_truth_;
  std::vector<Method> point_, cell_;
};

}  // namespace upd::app
