// Precision, recall, F1 and ROC of the non-traversable class (binary_metrics.h).
#include "upd/core/binary_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>

namespace upd::core {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void requireSameSize(std::size_t a, std::size_t b, const char* what) {
  if (a != b) {
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(a) +
                                " scores for " + std::to_string(b) + " truth labels");
  }
}

void count(BinaryCounts& c, bool flagged, Label truth) {
  if (truth == Label::Unknown) return;
  const bool positive = truth == Label::NonTraversable;
  if (flagged) {
    ++(positive ? c.tp : c.fp);
  } else {
    ++(positive ? c.fn : c.tn);
  }
}

}  // namespace

double BinaryCounts::precision() const { return tp + fp ? double(tp) / double(tp + fp) : kNaN; }
double BinaryCounts::recall() const { return tp + fn ? double(tp) / double(tp + fn) : kNaN; }
double BinaryCounts::f1() const {
  const std::size_t d = 2 * tp + fp + fn;
  return d ? 2.0 * double(tp) / double(d) : kNaN;
}
BinaryCounts& BinaryCounts::operator+=(const BinaryCounts& o) {
  tp += o.tp;
  fp += o.fp;
  tn += o.tn;
  fn += o.fn;
  return *this;
}

BinaryCounts countLabels(const std::vector<Label>& predicted, const std::vector<Label>& truth) {
  requireSameSize(predicted.size(), truth.size(), "countLabels");
  BinaryCounts c;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    count(c, predicted[i] == Label::NonTraversable, truth[i]);
  }
  return c;
}

BinaryCounts countThreshold(const std::vector<float>& score, float threshold,
                            const std::vector<Label>& truth) {
  requireSameSize(score.size(), truth.size(), "countThreshold");
  BinaryCounts c;
  for (std::size_t i = 0; i < truth.size(); ++i) count(c, score[i] >= threshold, truth[i]);
  return c;
}

RocCurve computeRoc(const std::vector<float>& score, const std::vector<Label>& truth) {
  requireSameSize(score.size(), truth.size(), "computeRoc");
  const float lowest = -std::numeric_limits<float>::infinity();
  std::vector<std::pair<float, bool>> ranked;  // (score, positive), scored truth only
  ranked.reserve(truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (truth[i] == Label::Unknown) continue;
    ranked.emplace_back(std::isnan(score[i]) ? lowest : score[i],
                        truth[i] == Label::NonTraversable);
  }
  std::sort(ranked.begin(), ranked.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  RocCurve roc;
  for (const auto& r : ranked) ++(r.second ? roc.positives : roc.negatives);
  roc.fpr.push_back(0);
  roc.tpr.push_back(0);
  roc.threshold.push_back(std::numeric_limits<float>::infinity());
  const double P = double(roc.positives), N = double(roc.negatives);
  std::size_t tp = 0, fp = 0;
  double area = 0;
  for (std::size_t i = 0; i < ranked.size();) {
    const float t = ranked[i].first;
    for (; i < ranked.size() && ranked[i].first == t; ++i) ++(ranked[i].second ? tp : fp);
    const double f = N > 0 ? fp / N : 0, r = P > 0 ? tp / P : 0;
    area += (f - roc.fpr.back()) * (r + roc.tpr.back()) / 2;
    roc.fpr.push_back(f);
    roc.tpr.push_back(r);
    roc.threshold.push_back(t);
    const double f1 = 2.0 * double(tp) / double(tp + fp + roc.positives);
    if (f1 > roc.best_f1) {
      roc.best_f1 = f1;
      roc.best_threshold = t;
    }
  }
  roc.auc = P > 0 && N > 0 ? area : kNaN;
  return roc;
}

RocCurve RocCurve::thinned(std::size_t n) const {
  if (fpr.size() <= n || n < 2) return *this;
  RocCurve out = *this;
  out.fpr.clear();
  out.tpr.clear();
  out.threshold.clear();
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = j * (fpr.size() - 1) / (n - 1);
    out.fpr.push_back(fpr[i]);
    out.tpr.push_back(tpr[i]);
    out.threshold.push_back(threshold[i]);
  }
  return out;
}

}  // namespace upd::core
