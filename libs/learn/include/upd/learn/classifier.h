// The learned traversability classifier: a model of OpenCV's ml module (random trees,
// boosting or an SVM) over the per-point features of upd/core/point_features.h, giving the
// probability that a point is non-traversable.
//
// It implements core::PointLabeler, so a pipeline with `[ClassifyParams] classifier = FILE`
// labels its points with it (registerLoader() makes core::loadPointLabeler read the files).
// Training balances the classes (at most max_samples / 2 points of each, drawn with a fixed
// seed) and standardizes the features (the SVM needs it; the trees do not care). The
// probability: random trees, the share of trees voting non-traversable; boosting and the SVM,
// a logistic of the raw decision value.
//
// A model file is an OpenCV FileStorage (.yml, .yaml, .xml or .json): the node
// `upd_point_classifier` (kind, FeatureParams, feature names, standardization, the sign of the
// raw output) and the node `model` (OpenCV's own); .gz: the same text, gzip-compressed. The
// text has a comment after its first line with the CRC-32 and length of the text after it (JSON,
// without comments: a member `upd_nav_crc32`), checked on reading (a .gz by gzip's own too), so
// that a file cut short or changed is refused as damage before OpenCV parses it. It is written through a temporary file renamed into place.
// Errors are std::runtime_error naming the file; bad arguments std::invalid_argument.
#pragma once

#include "upd/core/point_features.h"
#include "upd/core/point_labeler.h"

#include <memory>
#include <string>
#include <vector>

namespace upd::learn {

enum class ModelKind { RandomTrees, Boost, Svm };
/// "rtrees", "boost", "svm".
const char* toString(ModelKind kind);
/// Throws std::invalid_argument naming the valid names.
ModelKind parseModelKind(const std::string& name);

struct TrainParams {
  ModelKind kind = ModelKind::RandomTrees;
  int max_samples = 60000;  ///< training points, half of each class at most (SVM: 10000)
  int seed = 1;             ///< sampling seed
  int trees = 100;          ///< random trees: trees; boosting: weak learners
  int max_depth = 12;       ///< random trees' depth (boosting: 3)

  void validate() const;
};

class PointClassifier : public core::PointLabeler {
 public:
  /// Trains on features (row-major, kFeatureCount per point, as core::featuresOf gives) and
  /// truth (one per row; Unknown rows are skipped). Throws std::invalid_argument when a class
  /// has no point or the sizes disagree.
  static std::shared_ptr<PointClassifier> train(const std::vector<float>& features,
                                                const std::vector<core::Label>& truth,
                                                const core::FeatureParams& feature_params,
                                                const TrainParams& params);
  /// Reads a model file (header comment).
  static std::shared_ptr<PointClassifier> load(const std::string& path);
  /// Writes it atomically; the extension picks the format (.yml, .yaml, .xml, .json, each
  /// + .gz).
  void save(const std::string& path) const;

  /// Probability of non-traversable per row of features (core::PointLabeler).
  std::vector<float> probabilityOfFeatures(const std::vector<float>& features) const override;
  const core::FeatureParams& featureParams() const override;
  ModelKind kind() const;
  /// Random trees: the importance of each feature (kFeatureCount, summing to 1); else empty.
  std::vector<float> featureImportance() const;

  struct Impl;
  explicit PointClassifier(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

 private:
  std::shared_ptr<Impl> impl_;
};

/// Makes core::loadPointLabeler read model files with PointClassifier::load.
void registerLoader();

}  // namespace upd::learn
