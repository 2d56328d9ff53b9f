#include "upd/maps/step_edges.h"

#include <algorithm>
#include <cmath>

namespace upd::maps {

void StepEdgeParams::validate() const {
  const char* s = "StepEdgeParams";
  core::requireParam(std::isfinite(max_step_m) && max_step_m > 0, s, "max_step_m", max_step_m,
                     "must be > 0");
  core::requireParam(min_hits >= 1, s, "min_hits", min_hits, "must be >= 1");
  core::requireParam(std::isfinite(range_m) && range_m > 0, s, "range_m", range_m, "must be > 0");
}

std::vector<Eigen::Vector2d> findStepEdges(const TraversabilityGrid& grid,
                                           const Eigen::Vector2d& centre_xy,
                                           const StepEdgeParams& params) {
  params.validate();
  std::vector<Eigen::Vector2d> out;
  if (!params.enabled) return out;
  const int nx = grid.sizeX(), ny = grid.sizeY();
  const double cell = grid.cellSize();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Mean elevation of the window cell (cx, cy); NaN when outside or with too few points.
  const auto height = [&](int cx, int cy) {
    if (cx < 0 || cy < 0 || cx >= nx || cy >= ny) return nan;
    const GridCell& c = grid.at(cx, cy);
    return c.hits >= static_cast<std::uint32_t>(params.min_hits) && std::isfinite(c.elevation_m)
               ? static_cast<double>(c.elevation_m)
               : nan;
  };
  int cx0, cy0;
  if (!grid.cellIndex(std::clamp(centre_xy.x(), grid.xMin(), grid.xMax() - 0.5 * cell),
                      std::clamp(centre_xy.y(), grid.yMin(), grid.yMax() - 0.5 * cell), cx0, cy0)) {
    return out;
  }
  const int reach = static_cast<int>(std::ceil(params.range_m / cell));
  const double r2 = params.range_m * params.range_m;
  constexpr int kDirs[2][2] = {{1, 0}, {0, 1}};
  for (int cy = std::max(0, cy0 - reach); cy <= std::min(ny - 1, cy0 + reach); ++cy) {
    for (int cx = std::max(0, cx0 - reach); cx <= std::min(nx - 1, cx0 + reach); ++cx) {
      const Eigen::Vector2d c = grid.cellCenter(cx, cy);
      if ((c - centre_xy).squaredNorm() > r2) continue;
      for (const auto& d : kDirs) {
        // The ground of each side extrapolated to c; NaN when a cell has too few points.
        const double lo = height(cx - d[0], cy - d[1]), hi = height(cx + d[0], cy + d[1]);
        const double below = 2.0 * lo - height(cx - 2 * d[0], cy - 2 * d[1]);
        const double above = 2.0 * hi - height(cx + 2 * d[0], cy + 2 * d[1]);
        // Comparisons with NaN are false: a missing cell finds no edge.
        if (std::abs(above - below) > params.max_step_m && std::abs(hi - lo) > params.max_step_m) {
          out.push_back(c);
          break;
        }
      }
    }
  }
  return out;
}

}  // namespace upd::maps
