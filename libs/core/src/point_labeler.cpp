// The learned-classifier hook (point_labeler.h).
#include "upd/core/point_labeler.h"

#include <atomic>
#include <stdexcept>

namespace upd::core {

namespace {
std::atomic<PointLabelerLoader> g_loader{nullptr};
}  // namespace

void setPointLabelerLoader(PointLabelerLoader loader) { g_loader = loader; }

std::shared_ptr<const PointLabeler> loadPointLabeler(const std::string& path) {
  const PointLabelerLoader loader = g_loader;
  if (!loader) {
    throw std::runtime_error("classifier '" + path +
                             "': this build has no learned classifier (libs/learn needs "
                             "OpenCV's ml module)");
  }
  return loader(path);
}

void applyPointLabeler(const PointLabeler& labeler, const PointCloud& cloud,
                       const Normals& normals, const Eigen::Vector3f& up, Classification& out) {
  const std::vector<float> p = labeler.probability(cloud, normals, up);
  if (p.size() != out.label.size()) {
    throw std::runtime_error("classifier: " + std::to_string(p.size()) + " probabilities for " +
                             std::to_string(out.label.size()) + " points");
  }
  out.traversable = out.non_traversable = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (out.label[i] == Label::Unknown) continue;
    const bool obstacle = p[i] >= labeler.threshold();
    out.label[i] = obstacle ? Label::NonTraversable : Label::Traversable;
    out.cost[i] = obstacle ? 1.f : p[i];
    ++(obstacle ? out.non_traversable : out.traversable);
  }
}

}  // namespace upd::core
