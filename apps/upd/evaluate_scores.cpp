// Scoring labelled clouds and pooling the results (evaluate_scores.h).
#include "evaluate_scores.h"

#include "run_config.h"

#include "upd/core/classify.h"
#include "upd/core/kdtree.h"
#include "upd/core/preprocess.h"
#include "upd/nav/nav_config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

namespace upd::app {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr double kSlopeAloneMax_rad = 20.0 * core::kDegToRad;  // the one-line rules
constexpr double kHeightRangeMax_m = 0.3;

core::PipelineParams paramsFor(const LabelledCloud& in, const EvalSettings& s) {
  const std::string path = !s.config.empty()
                               ? s.config
                               : (std::filesystem::path(nav::defaultConfigDir()) / in.config).string();
  core::PipelineParams p = loadRunConfig(path).observer.pipeline;
  p.up = in.up;
  return p;
}

// Each kept point takes the label of the nearest input point.
std::vector<core::Label> transferTruth(const LabelledCloud& in, const core::PointCloud& kept) {
  core::PointCloud finite;
  std::vector<core::Label> finite_truth;
  for (std::size_t i = 0; i < in.cloud.size(); ++i) {
    if (!in.cloud.isFinite(i)) continue;
    finite.push_back(in.cloud.x[i], in.cloud.y[i], in.cloud.z[i]);
    finite_truth.push_back(in.truth[i]);
  }
  std::vector<core::Label> out(kept.size(), core::Label::Unknown);
  if (finite.empty()) return out;
  const core::KdTree tree(finite);
  std::vector<std::uint32_t> nn;
  for (std::size_t i = 0; i < kept.size(); ++i) {
    if (!kept.isFinite(i)) continue;
    tree.knnSearch(kept.point(i), 1, nn);
    if (!nn.empty()) out[i] = finite_truth[nn[0]];
  }
  return out;
}

std::vector<double> radiiToScore(const EvalSettings& s) {
  std::vector<double> r = s.radii_m;
  for (double f : s.features.radii()) {
    if (std::find(r.begin(), r.end(), f) == r.end()) r.push_back(f);
  }
  return r;
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

Method thresholdMethod(std::string name, double radius_m, std::vector<float> score, float t,
                       std::string rule) {
  Method m{std::move(name), radius_m, std::move(rule), std::move(score), {}};
  m.label.resize(m.score.size());
  for (std::size_t i = 0; i < m.score.size(); ++i) {
    m.label[i] = std::isnan(m.score[i])  ? core::Label::Unknown
                 : m.score[i] >= t       ? core::Label::NonTraversable
                                         : core::Label::Traversable;
  }
  return m;
}

// The UPD at one d_m: the classifier rule of classify.h and its continuous form, the larger of
// (1 - zeta) / (1 - zeta_min) and slope / max_slope (>= 1 where the rule flags).
void addUpd(std::vector<Method>& out, const core::RadiusScores& r, const ProcessedCloud& pc) {
  const core::ClassifyParams& c = pc.params.classify;
  const std::size_t n = r.upd.size();
  std::vector<float> combined(n, kNaN), one_minus_zeta(n, kNaN);
  for (std::size_t i = 0; i < n; ++i) {
    if (!r.upd.isValid(i)) continue;
    one_minus_zeta[i] = 1.f - r.upd.zeta[i];
    combined[i] = std::max<float>(one_minus_zeta[i] / (1.0 - c.zeta_min),
                                  r.upd_slope_rad[i] / c.max_slope_rad);
  }
  const double deg = c.max_slope_rad * core::kRadToDeg;
  Method rule{"UPD (zeta and slope)", r.radius_m,
              fmt("zeta < %.2f", c.zeta_min) + fmt(" or slope of r > %.0f deg", deg), combined, {}};
  rule.label = core::classify(r.upd, pc.up, c).label;
  out.push_back(std::move(rule));
  out.push_back(thresholdMethod("UPD zeta alone", r.radius_m, one_minus_zeta,
                                static_cast<float>(1.0 - c.zeta_min), fmt("zeta < %.2f", c.zeta_min)));
  out.push_back(thresholdMethod("UPD slope of r alone", r.radius_m, r.upd_slope_rad,
                                static_cast<float>(c.max_slope_rad), fmt("slope of r > %.0f deg", deg)));
}

}  // namespace

ProcessedCloud processCloud(const LabelledCloud& in, const EvalSettings& s) {
  ProcessedCloud pc;
  pc.params = paramsFor(in, s);
  pc.up = in.up.normalized();
  pc.cloud = core::preprocess(in.cloud, pc.params.preprocess);
  pc.truth = transferTruth(in, pc.cloud);
  const core::KdTree tree(pc.cloud);
  const core::Normals normals = core::computeNormals(pc.cloud, tree, pc.params.normals, pc.up);
  pc.scores = core::computePointScores(pc.cloud, tree, normals, pc.up, radiiToScore(s),
                                       s.features.cell_m, s.features.min_neighbors);
  pc.features = core::featuresOf(pc.scores, s.features);
  if (s.classifier) pc.classifier = s.classifier->probabilityOfFeatures(pc.features);
  return pc;
}

std::vector<Method> methodsOf(const ProcessedCloud& pc, const EvalSettings& s) {
  std::vector<Method> out;
  const core::BaselineParams base;
  for (double d : s.radii_m) {
    const core::RadiusScores& r = pc.scores.at(d);
    addUpd(out, r, pc);
    out.push_back(thresholdMethod("roughness index", d, r.baselines.roughness_m,
                                  static_cast<float>(base.roughness_max_m),
                                  fmt("std dev of elevation > %.2f m", base.roughness_max_m)));
    out.push_back(thresholdMethod("inclination index", d, r.baselines.inclination_rad,
                                  static_cast<float>(base.max_inclination_rad),
                                  fmt("plane fit > %.0f deg", base.max_inclination_rad * core::kRadToDeg)));
  }
  out.push_back(thresholdMethod("slope alone (normal)", 0, pc.scores.normal_slope_rad,
                                static_cast<float>(kSlopeAloneMax_rad), "normal > 20 deg"));
  out.push_back(thresholdMethod("height range", 0, pc.scores.height_range_m,
                                static_cast<float>(kHeightRangeMax_m),
                                fmt("> 0.3 m in %.1f m cells", s.features.cell_m)));
  if (s.classifier) {
    out.push_back(thresholdMethod("learned classifier", 0, pc.classifier,
                                  s.classifier->threshold(), "probability >= 0.5"));
  }
  return out;
}

void GroupPool::add(const ProcessedCloud& pc, const EvalSettings& s) {
  std::vector<Method> methods = methodsOf(pc, s);
  if (point_.empty()) {
    point_ = methods;
    cell_ = methods;
    for (auto* v : {&point_, &cell_}) {
      for (Method& m : *v) m.score.clear(), m.label.clear();
    }
  }
  ++clouds_;
  point_truth_.insert(point_truth_.end(), pc.truth.begin(), pc.truth.end());
  // Cells: truth obstacle if any point is, score the highest, label obstacle if any point is.
  std::size_t columns = 0;
  const std::vector<std::uint32_t> col = core::columnIndex(pc.cloud, pc.up, s.cell_m, columns);
  const std::size_t base = cell_truth_.size();
  cell_truth_.resize(base + columns, core::Label::Unknown);
  for (std::size_t i = 0; i < col.size(); ++i) {
    if (col[i] == core::kNoColumn || pc.truth[i] == core::Label::Unknown) continue;
    core::Label& t = cell_truth_[base + col[i]];
    if (t != core::Label::NonTraversable) t = pc.truth[i];
  }
  for (std::size_t k = 0; k < methods.size(); ++k) {
    Method& m = methods[k];
    Method& p = point_[k];
    p.score.insert(p.score.end(), m.score.begin(), m.score.end());
    p.label.insert(p.label.end(), m.label.begin(), m.label.end());
    Method& c = cell_[k];
    c.score.resize(base + columns, kNaN);
    c.label.resize(base + columns, core::Label::Unknown);
    for (std::size_t i = 0; i < col.size(); ++i) {
      if (col[i] == core::kNoColumn) continue;
      float& cs = c.score[base + col[i]];
      if (!std::isnan(m.score[i]) && !(cs >= m.score[i])) cs = m.score[i];
      core::Label& cl = c.label[base + col[i]];
      if (cl != core::Label::NonTraversable && m.label[i] != core::Label::Unknown) cl = m.label[i];
    }
  }
}

std::vector<MethodResult> GroupPool::results(const std::vector<core::Label>& truth,
                                             const std::vector<Method>& methods) {
  std::vector<MethodResult> out;
  for (const Method& m : methods) {
    MethodResult r{m.name, m.rule, m.radius_m, core::countLabels(m.label, truth),
                   core::computeRoc(m.score, truth)};
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace upd::app
