#include "upd/nav/negative_obstacles.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace upd::nav {

void NegativeObstacleParams::validate() const {
  core::requireParam(std::isfinite(min_gap_m) && min_gap_m > 0, "NegativeObstacleParams", "min_gap_m",
               min_gap_m, "must be > 0");
  core::requireParam(std::isfinite(min_drop_m) && min_drop_m > 0, "NegativeObstacleParams", "min_drop_m",
               min_drop_m, "must be > 0");
  core::requireParam(std::isfinite(max_range_m) && max_range_m > 0, "NegativeObstacleParams",
               "max_range_m", max_range_m, "must be > 0");
}

std::vector<GroundGap> findGroundGaps(const core::PointCloud& cloud, double ground_z_m,
                                      const NegativeObstacleParams& params) {
  params.validate();
  std::vector<GroundGap> gaps;
  if (!params.enabled || !cloud.isOrganized()) return gaps;
  const std::size_t w = cloud.width, h = cloud.height;
  const Eigen::Vector3f origin = cloud.sensor_origin;
  const double gap2 = params.min_gap_m * params.min_gap_m;
  const double range2 = params.max_range_m * params.max_range_m;
  for (std::size_t u = 0; u < w; ++u) {
    bool have_prev = false;
    Eigen::Vector3f prev = Eigen::Vector3f::Zero();
    for (std::size_t k = 0; k < h; ++k) {
      const std::size_t i = (h - 1 - k) * w + u;  // bottom row first: near to far
      if (!cloud.isFinite(i)) continue;
      const Eigen::Vector3f p = cloud.point(i);
      if (have_prev && (prev - origin).squaredNorm() <= range2) {
        const double dx = p.x() - prev.x(), dy = p.y() - prev.y();
        const double below = std::min<double>(prev.z(), ground_z_m) - params.min_drop_m;
        if (dx * dx + dy * dy >= gap2 && p.z() < below) {
          gaps.push_back({prev.cast<double>(), p.cast<double>()});
        }
      }
      prev = p;
      have_prev = true;
    }
  }
  return gaps;
}

std::vector<Eigen::Vector2d> sampleGap(const GroundGap& gap, double spacing_m) {
  if (!(spacing_m > 0) || !std::isfinite(spacing_m)) {
    throw std::invalid_argument("sampleGap: spacing_m = " + std::to_string(spacing_m) +
                                ": must be > 0");
  }
  const Eigen::Vector2d a = gap.near_world.head<2>(), b = gap.far_world.head<2>();
  const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing_m)));
  std::vector<Eigen::Vector2d> pts;
  pts.reserve(static_cast<std::size_t>(n) + 1);
  for (int i = 0; i <= n; ++i) pts.push_back(a + (b - a) * (static_cast<double>(i) / n));
  return pts;
}

}  // namespace upd::nav
