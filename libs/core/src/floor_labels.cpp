// Geometric labels from the floor plane (floor_labels.h).
#include "upd/core/floor_labels.h"

#include "upd/core/kdtree.h"

#include <cmath>
#include <stdexcept>

namespace upd::core {

void GeometricLabelParams::validate() const {
  requireParam(off_floor_m > 0 && off_floor_m < 1, "GeometricLabelParams", "off_floor_m",
               off_floor_m, "must be in (0, 1)");
  requireParam(border_m >= 0 && border_m < 2, "GeometricLabelParams", "border_m", border_m,
               "must be in [0, 2)");
}

std::vector<Label> labelByFloor(const PointCloud& cloud, const FloorPlane& plane,
                                const GeometricLabelParams& params) {
  params.validate();
  if (!plane.found) throw std::invalid_argument("labelByFloor: no floor plane (" + plane.failure + ")");
  const Eigen::Vector3f n = plane.normal.cast<float>();
  const float d = static_cast<float>(plane.offset_m);
  std::vector<Label> labels(cloud.size(), Label::Unknown);
  PointCloud off;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.isFinite(i)) continue;
    const bool on_floor = std::abs(n.dot(cloud.point(i)) + d) <= params.off_floor_m;
    labels[i] = on_floor ? Label::Traversable : Label::NonTraversable;
    if (!on_floor) off.push_back(cloud.x[i], cloud.y[i], cloud.z[i]);
  }
  if (off.empty() || params.border_m <= 0) return labels;
  const KdTree tree(off);
  std::vector<std::uint32_t> near;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (labels[i] != Label::Traversable) continue;
    tree.radiusSearch(cloud.point(i), static_cast<float>(params.border_m), near);
    if (!near.empty()) labels[i] = Label::NonTraversable;
  }
  return labels;
}

}  // namespace upd::core
