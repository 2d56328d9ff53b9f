// The state of a PointClassifier, shared by its training and its file format (not installed).
#pragma once

#include "upd/learn/classifier.h"

#include <opencv2/core.hpp>
#include <opencv2/ml.hpp>

namespace upd::learn {

struct PointClassifier::Impl {
  ModelKind kind = ModelKind::RandomTrees;
  core::FeatureParams features;
  cv::Mat mean, scale;   // 1 x kFeatureCount, CV_32F: x' = (x - mean) * scale
  float raw_sign = 1.f;  // boosting and SVM: +1 when a raw output > 0 means non-traversable
  cv::Ptr<cv::ml::StatModel> model;

  /// rows x kFeatureCount standardized features.
  cv::Mat standardized(const std::vector<float>& f) const;
};

}  // namespace upd::learn
