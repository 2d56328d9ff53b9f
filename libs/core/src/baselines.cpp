#include "upd/core/baselines.h"

#include "upd/core/normals.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace upd::core {

void BaselineParams::validate() const {
  requireParam(std::isfinite(radius_m) && radius_m > 0, "BaselineParams", "radius_m", radius_m,
               "must be > 0");
  requireParam(std::isfinite(roughness_max_m) && roughness_max_m > 0, "BaselineParams",
               "roughness_max_m", roughness_max_m, "must be > 0");
  requireParam(max_inclination_rad > 0 && max_inclination_rad <= 0.5 * M_PI, "BaselineParams",
               "max_inclination_deg", max_inclination_rad * kRadToDeg, "must be in (0, 90]");
  requireParam(min_neighbors >= 3, "BaselineParams", "min_neighbors", min_neighbors,
               "must be >= 3");
}

BaselineResult computeBaselines(const PointCloud& cloud, const KdTree& tree,
                                const Eigen::Vector3f& up, const BaselineParams& params) {
  params.validate();
  const std::size_t n_pts = cloud.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  BaselineResult out;
  out.roughness_m.assign(n_pts, nan);
  out.inclination_rad.assign(n_pts, nan);
  out.roughness_label.assign(n_pts, Label::Unknown);
  const float radius = static_cast<float>(params.radius_m);
  const Eigen::Vector3d up_d = up.cast<double>();
  std::size_t invalid = 0;

#pragma omp parallel reduction(+ : invalid)
  {
    std::vector<std::uint32_t> nb;
    const std::vector<float> no_weights;
#pragma omp for schedule(dynamic, 256)
    for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n_pts); ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      if (!cloud.isFinite(i)) {
        ++invalid;
        continue;
      }
      const Eigen::Vector3f p = cloud.point(i);
      tree.radiusSearch(p, radius, nb);
      if (nb.size() < static_cast<std::size_t>(params.min_neighbors)) {
        ++invalid;
        continue;
      }
      // Elevation relative to the query point: exact far from the origin.
      double s = 0, s2 = 0;
      for (const std::uint32_t j : nb) {
        const double e = (cloud.point(j) - p).cast<double>().dot(up_d);
        s += e;
        s2 += e * e;
      }
      const double mean = s / nb.size();
      const double roughness = std::sqrt(std::max(0.0, s2 / nb.size() - mean * mean));
      out.roughness_m[i] = static_cast<float>(roughness);
      out.roughness_label[i] =
          roughness > params.roughness_max_m ? Label::NonTraversable : Label::Traversable;
      Eigen::Vector3f n;
      float curvature;
      if (pcaNormal(cloud, nb, no_weights, n, curvature)) {
        out.inclination_rad[i] = std::acos(std::min(1.f, std::abs(n.dot(up))));
      }
    }
  }
  out.invalid = invalid;
  return out;
}

}  // namespace upd::core
