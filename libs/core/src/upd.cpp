#include "upd/core/upd.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace upd::core {

void UpdParams::validate() const {
  requireParam(std::isfinite(radius_m) && radius_m > 0, "UpdParams", "radius_m", radius_m,
               "must be > 0");
  requireParam(knn == 0 || knn >= 3, "UpdParams", "knn", knn, "must be 0 (radius) or >= 3");
  requireParam(min_neighbors >= 1, "UpdParams", "min_neighbors", min_neighbors, "must be >= 1");
  requireParam(enumName(kUpdMethodNames, method) != nullptr, "UpdParams", "method",
               static_cast<int>(method), "must be auto, exact or fast");
  requireParam(method != UpdMethod::Fast || knn == 0, "UpdParams", "method", "fast",
               "the fast path sums over the radius d_m: it needs knn = 0");
  requireParam(fast_cells_per_radius >= 2 && fast_cells_per_radius <= 16, "UpdParams",
               "fast_cells_per_radius", fast_cells_per_radius, "must be in [2, 16]");
  requireParam(std::isfinite(fast_cells_per_point) && fast_cells_per_point >= 0, "UpdParams",
               "fast_cells_per_point", fast_cells_per_point, "must be >= 0");
  requireParam(std::isfinite(fast_refine_spread) && fast_refine_spread >= 0, "UpdParams",
               "fast_refine_spread", fast_refine_spread, "must be >= 0");
  requireParam(std::isfinite(fast_exact_band) && fast_exact_band >= 0, "UpdParams",
               "fast_exact_band", fast_exact_band, "must be >= 0");
}

UpdResult computeUpd(const PointCloud& cloud, const KdTree& tree, const Normals& normals,
                     const UpdParams& params) {
  params.validate();
  const std::size_t n_pts = cloud.size();
  if (normals.size() != n_pts) {
    throw std::invalid_argument("computeUpd: " + std::to_string(normals.size()) +
                                " normals for " + std::to_string(n_pts) + " points");
  }
  UpdResult out = UpdResult::unscored(n_pts);
  const float radius = static_cast<float>(params.radius_m);
  std::size_t invalid = 0;

#pragma omp parallel reduction(+ : invalid)
  {
    std::vector<std::uint32_t> nb;
#pragma omp for schedule(dynamic, 256)
    for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n_pts); ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      if (!cloud.isFinite(i)) {
        ++invalid;
        continue;
      }
      if (params.knn > 0) {
        tree.knnSearch(cloud.point(i), params.knn, nb);
      } else {
        tree.radiusSearch(cloud.point(i), radius, nb);
      }
      // Eq. 6: r = sum of the unit normals of the neighbourhood (invalid normals skipped).
      double sx = 0, sy = 0, sz = 0;
      std::uint32_t k = 0;
      for (const std::uint32_t j : nb) {
        if (!normals.isValid(j)) continue;
        sx += normals.nx[j];
        sy += normals.ny[j];
        sz += normals.nz[j];
        ++k;
      }
      if (k < static_cast<std::uint32_t>(params.min_neighbors)) {
        ++invalid;
        continue;
      }
      out.rx[i] = static_cast<float>(sx);
      out.ry[i] = static_cast<float>(sy);
      out.rz[i] = static_cast<float>(sz);
      // Eq. 8: zeta = |r| / k.
      out.zeta[i] = static_cast<float>(std::sqrt(sx * sx + sy * sy + sz * sz) / k);
      out.k[i] = k;
    }
  }
  out.invalid = invalid;
  return out;
}

}  // namespace upd::core
