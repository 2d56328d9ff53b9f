// Scores of a traversability detector against a ground truth: precision, recall and F1 of the
// non-traversable class, and the ROC curve and its area for a continuous score.
//
// The positive class is NonTraversable. A point whose truth is Unknown carries no truth and is
// not counted. A predicted Unknown (a point the detector could not score) counts as not
// flagged: a detector is not forgiven the points it cannot score. In the same way a NaN
// score ranks below every finite score (it is flagged by no threshold but the last, which
// flags everything).
//
// ROC: the points are sorted by score, highest first; every distinct score is one threshold
// ("flag the points with score >= t"), so tied points enter the curve together and the area
// (trapezoids) equals the Mann-Whitney probability that a random positive outranks a random
// negative, ties counting one half.
#pragma once

#include "upd/core/point_cloud.h"

#include <cstddef>
#include <vector>

namespace upd::core {

/// The confusion counts of the non-traversable class.
struct BinaryCounts {
  std::size_t tp = 0, fp = 0, tn = 0, fn = 0;

  std::size_t positives() const { return tp + fn; }
  std::size_t negatives() const { return fp + tn; }
  double precision() const;  ///< tp / (tp + fp); NaN when nothing is flagged
  double recall() const;     ///< tp / (tp + fn); NaN when the truth holds no positive
  double f1() const;         ///< 2 tp / (2 tp + fp + fn); NaN when both are empty
  BinaryCounts& operator+=(const BinaryCounts& o);
};

/// Counts predicted against truth (same size; std::invalid_argument otherwise).
BinaryCounts countLabels(const std::vector<Label>& predicted, const std::vector<Label>& truth);

/// Counts "score >= threshold" against truth (same size; NaN scores are not flagged).
BinaryCounts countThreshold(const std::vector<float>& score, float threshold,
                            const std::vector<Label>& truth);

struct RocCurve {
  /// One point per distinct score from the highest, starting at (0, 0) with threshold +inf
  /// and ending at (1, 1).
  std::vector<double> fpr, tpr;
  std::vector<float> threshold;  ///< flag score >= threshold[i] to be at point i
  double auc = 0;                ///< area under the curve; NaN without positives or negatives
  std::size_t positives = 0, negatives = 0;
  double best_f1 = 0;            ///< the highest F1 over the thresholds
  float best_threshold = 0;      ///< ... and its threshold

  /// At most n points (the first, the last and evenly spaced ones between), for plots and
  /// JSON.
  RocCurve thinned(std::size_t n) const;
};

/// The ROC of score (higher = more likely non-traversable) against truth (same size;
/// std::invalid_argument otherwise).
RocCurve computeRoc(const std::vector<float>& score, const std::vector<Label>& truth);

}  // namespace upd::core
