// Precision, recall, F1 and ROC against hand-computed cases and a brute-force Mann-Whitney AUC.
#include "upd/core/binary_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace upd::core {
namespace {

constexpr Label P = Label::NonTraversable, N = Label::Traversable, U = Label::Unknown;

TEST(BinaryMetrics, CountsPrecisionRecallF1) {
  // tp 2, fp 1, fn 1, tn 1; the Unknown truth is not counted, a predicted Unknown is a miss.
  const std::vector<Label> pred = {P, P, P, N, U, N, P};
  const std::vector<Label> truth = {P, P, N, P, P, N, U};
  const BinaryCounts c = countLabels(pred, truth);
  EXPECT_EQ(c.tp, 2u);
  EXPECT_EQ(c.fp, 1u);
  EXPECT_EQ(c.fn, 2u);
  EXPECT_EQ(c.tn, 1u);
  EXPECT_DOUBLE_EQ(c.precision(), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(c.recall(), 0.5);
  EXPECT_DOUBLE_EQ(c.f1(), 4.0 / 7.0);
  EXPECT_TRUE(std::isnan(BinaryCounts{}.f1()));
  EXPECT_THROW(countLabels({P}, {P, N}), std::invalid_argument);
}

TEST(BinaryMetrics, ThresholdFlagsScoresAtOrAboveIt) {
  const std::vector<float> s = {0.9f, 0.5f, NAN, 0.2f};
  const BinaryCounts c = countThreshold(s, 0.5f, {P, N, P, N});
  EXPECT_EQ(c.tp, 1u);
  EXPECT_EQ(c.fp, 1u);
  EXPECT_EQ(c.fn, 1u);  // NaN is never flagged
  EXPECT_EQ(c.tn, 1u);
}

TEST(BinaryMetrics, AucOfKnownRankings) {
  EXPECT_DOUBLE_EQ(computeRoc({4, 3, 2, 1}, {P, P, N, N}).auc, 1.0);
  EXPECT_DOUBLE_EQ(computeRoc({4, 3, 2, 1}, {N, N, P, P}).auc, 0.0);
  // Pairs (P, N): (4, 3) (4, 1) (2, 1) won, (2, 3) lost: 3 / 4.
  EXPECT_DOUBLE_EQ(computeRoc({4, 3, 2, 1}, {P, N, P, N}).auc, 0.75);
  // All tied: one half; NaN ranks below every number.
  EXPECT_DOUBLE_EQ(computeRoc({1, 1, 1, 1}, {P, N, P, N}).auc, 0.5);
  EXPECT_DOUBLE_EQ(computeRoc({NAN, 1, NAN, 2}, {P, N, P, N}).auc, 0.0);
  // Unknown truth is left out; no negatives: NaN area.
  EXPECT_DOUBLE_EQ(computeRoc({4, 9, 3}, {P, U, N}).auc, 1.0);
  EXPECT_TRUE(std::isnan(computeRoc({1, 2}, {P, P}).auc));
}

TEST(BinaryMetrics, CurveRunsFromOriginToOneAndFindsTheBestF1) {
  const RocCurve roc = computeRoc({0.9f, 0.8f, 0.7f, 0.1f}, {P, P, N, N});
  ASSERT_EQ(roc.fpr.size(), 5u);
  EXPECT_EQ(roc.fpr.front(), 0.0);
  EXPECT_EQ(roc.tpr.front(), 0.0);
  EXPECT_EQ(roc.fpr.back(), 1.0);
  EXPECT_EQ(roc.tpr.back(), 1.0);
  EXPECT_DOUBLE_EQ(roc.best_f1, 1.0);
  EXPECT_FLOAT_EQ(roc.best_threshold, 0.8f);
  EXPECT_EQ(roc.positives, 2u);
  EXPECT_EQ(roc.negatives, 2u);
  const RocCurve thin = computeRoc(std::vector<float>(100, 0) , std::vector<Label>(100, P));
  EXPECT_LE(thin.thinned(10).fpr.size(), 10u);
}

TEST(BinaryMetrics, AucEqualsMannWhitneyWithTies) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> level(0, 9);  // few levels: many ties
  std::bernoulli_distribution positive(0.3);
  std::vector<float> s(400);
  std::vector<Label> t(400);
  for (std::size_t i = 0; i < s.size(); ++i) {
    t[i] = positive(rng) ? P : N;
    s[i] = float(level(rng) + (t[i] == P ? 2 : 0));
  }
  double wins = 0, pairs = 0;
  for (std::size_t i = 0; i < s.size(); ++i) {
    for (std::size_t j = 0; j < s.size(); ++j) {
      if (t[i] != P || t[j] != N) continue;
      pairs += 1;
      wins += s[i] > s[j] ? 1.0 : s[i] == s[j] ? 0.5 : 0.0;
    }
  }
  EXPECT_NEAR(computeRoc(s, t).auc, wins / pairs, 1e-12);
}

}  // namespace
}  // namespace upd::core
