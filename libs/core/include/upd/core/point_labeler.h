// The hook of a learned classifier in the pipeline: when PipelineParams::labeler is set, the
// per-point label comes from the model instead of the threshold rule of classify.h.
//
// The core only knows this interface (it stays Eigen-only); the model itself, OpenCV's `ml`,
// lives in libs/learn, which registers its loader with setPointLabelerLoader at start-up. A
// config names the model with `[ClassifyParams] classifier = FILE`; loadPointLabeler then
// reads it, and throws when no loader was registered (a build without libs/learn).
//
// With a labeler, a point the UPD could not score stays Unknown (cost NaN); every other point
// is NonTraversable (cost 1) when the model's probability of non-traversable is >= its
// threshold, else Traversable with cost = that probability.
#pragma once

#include "upd/core/classify.h"
#include "upd/core/normals.h"
#include "upd/core/point_cloud.h"
#include "upd/core/point_features.h"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace upd::core {

class PointLabeler {
 public:
  virtual ~PointLabeler() = default;
  /// The features the model reads (point_features.h).
  virtual const FeatureParams& featureParams() const = 0;
  /// The probability of NonTraversable, in [0, 1], of each row of features (row-major,
  /// kFeatureCount per point, as featuresOf gives them).
  virtual std::vector<float> probabilityOfFeatures(const std::vector<float>& features) const = 0;
  /// The same for every point of cloud (its normals unit or NaN, up unit): computeFeatures,
  /// then probabilityOfFeatures.
  virtual std::vector<float> probability(const PointCloud& cloud, const Normals& normals,
                                         const Eigen::Vector3f& up) const {
    return probabilityOfFeatures(computeFeatures(cloud, normals, up, featureParams()));
  }
  /// Points with probability >= this are NonTraversable.
  virtual float threshold() const { return 0.5f; }
};

using PointLabelerLoader = std::shared_ptr<const PointLabeler> (*)(const std::string& path);

/// Registers the loader of model files (libs/learn does; the last call wins).
void setPointLabelerLoader(PointLabelerLoader loader);
/// Loads the model at path with the registered loader. Throws std::runtime_error when none is
/// registered, and whatever the loader throws for a bad file.
std::shared_ptr<const PointLabeler> loadPointLabeler(const std::string& path);

/// Relabels out (the rule's classification of the same points) by the labeler, as the header
/// comment says.
void applyPointLabeler(const PointLabeler& labeler, const PointCloud& cloud,
                       const Normals& normals, const Eigen::Vector3f& up, Classification& out);

}  // namespace upd::core
