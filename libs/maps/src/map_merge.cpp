#include "upd/maps/map_merge.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace upd::maps {

namespace {

// Mean of two means weighted by their counts; NaN when both counts are 0.
float weightedMean(float a, std::uint32_t na, float b, std::uint32_t nb) {
  if (na == 0 || std::isnan(a)) return nb == 0 ? GridCell::kNaN : b;
  if (nb == 0 || std::isnan(b)) return a;
  return static_cast<float>((static_cast<double>(a) * na + static_cast<double>(b) * nb) /
                            (static_cast<double>(na) + nb));
}

std::uint32_t addSaturating(std::uint32_t a, std::uint32_t b) {
  return b > std::numeric_limits<std::uint32_t>::max() - a
             ? std::numeric_limits<std::uint32_t>::max()
             : a + b;
}

void requireSameCellSize(double a, double b, const char* what) {
  if (std::abs(a - b) > 1e-9 * std::max(a, b)) {
    throw std::invalid_argument(std::string(what) + ": cell sizes differ (" + std::to_string(a) +
                                " m and " + std::to_string(b) + " m)");
  }
}

}  // namespace

GridCell mergeCells(const GridCell& a, const GridCell& b, const FusionParams& fusion) {
  if (!b.observed()) return a;
  if (!a.observed()) return b;
  GridCell c;
  const double sum = (std::isnan(a.logodds_nontrav) ? 0.0 : a.logodds_nontrav) +
                     (std::isnan(b.logodds_nontrav) ? 0.0 : b.logodds_nontrav);
  c.logodds_nontrav = std::isnan(a.logodds_nontrav) && std::isnan(b.logodds_nontrav)
                          ? GridCell::kNaN
                          : fuseLogOdds(0.f, sum, fusion);
  c.zeta_min = std::fmin(a.zeta_min, b.zeta_min);
  c.zeta_mean = weightedMean(a.zeta_mean, a.zeta_count, b.zeta_mean, b.zeta_count);
  c.slope_rad = weightedMean(a.slope_rad, a.slope_count, b.slope_rad, b.slope_count);
  c.cost_mean = weightedMean(a.cost_mean, a.cost_count, b.cost_mean, b.cost_count);
  c.elevation_m = weightedMean(a.elevation_m, a.hits, b.elevation_m, b.hits);
  c.elevation_max_m = std::fmax(a.elevation_max_m, b.elevation_max_m);
  c.hits = addSaturating(a.hits, b.hits);
  c.zeta_count = addSaturating(a.zeta_count, b.zeta_count);
  c.slope_count = addSaturating(a.slope_count, b.slope_count);
  c.cost_count = addSaturating(a.cost_count, b.cost_count);
  c.last_seen_s = std::fmax(a.last_seen_s, b.last_seen_s);
  return c;
}

GridParams fixedWindowParams(const GridParams& base, std::int64_t i0, std::int64_t j0,
                             std::int64_t cells_x, std::int64_t cells_y) {
  const std::int64_t n = std::max<std::int64_t>({cells_x, cells_y, 2});
  GridParams p = base;
  p.follow_robot = false;
  p.extent_m = static_cast<double>(n) * p.cell_size_m;
  // floor(center / cell) - n / 2 is the first cell (TraversabilityGrid's constructor).
  p.center_x_m = (static_cast<double>(i0 + n / 2) + 0.5) * p.cell_size_m;
  p.center_y_m = (static_cast<double>(j0 + n / 2) + 0.5) * p.cell_size_m;
  return p;
}

TraversabilityGrid windowCovering(const TraversabilityGrid& a, const TraversabilityGrid& b) {
  requireSameCellSize(a.cellSize(), b.cellSize(), "windowCovering");
  const std::int64_t i0 = std::min(a.originI(), b.originI());
  const std::int64_t j0 = std::min(a.originJ(), b.originJ());
  const std::int64_t i1 = std::max(a.originI() + a.sizeX(), b.originI() + b.sizeX());
  const std::int64_t j1 = std::max(a.originJ() + a.sizeY(), b.originJ() + b.sizeY());
  return TraversabilityGrid(fixedWindowParams(a.params(), i0, j0, i1 - i0, j1 - j0));
}

std::size_t mergeGridInto(TraversabilityGrid& into, const TraversabilityGrid& from,
                          const FusionParams& fusion) {
  requireSameCellSize(into.cellSize(), from.cellSize(), "mergeGridInto");
  std::size_t outside = 0;
  for (int cy = 0; cy < from.sizeY(); ++cy) {
    for (int cx = 0; cx < from.sizeX(); ++cx) {
      const GridCell& src = from.at(cx, cy);
      if (!src.observed()) continue;
      const std::int64_t tx = from.originI() + cx - into.originI();
      const std::int64_t ty = from.originJ() + cy - into.originJ();
      if (tx < 0 || ty < 0 || tx >= into.sizeX() || ty >= into.sizeY()) {
        ++outside;
        continue;
      }
      GridCell& dst = into.at(static_cast<int>(tx), static_cast<int>(ty));
      dst = mergeCells(dst, src, fusion);
    }
  }
  return outside;
}

TraversabilityGrid cropGrid(const TraversabilityGrid& grid, const Region& r) {
  if (!(r.x_max > r.x_min && r.y_max > r.y_min) || !std::isfinite(r.x_min + r.x_max + r.y_min + r.y_max)) {
    throw std::invalid_argument("region " + std::to_string(r.x_min) + "," +
                                std::to_string(r.y_min) + "," + std::to_string(r.x_max) + "," +
                                std::to_string(r.y_max) + ": must have x_max > x_min and y_max > y_min");
  }
  const double cell = grid.cellSize();
  const auto i0 = static_cast<std::int64_t>(std::floor(r.x_min / cell));
  const auto j0 = static_cast<std::int64_t>(std::floor(r.y_min / cell));
  const auto i1 = static_cast<std::int64_t>(std::ceil(r.x_max / cell));
  const auto j1 = static_cast<std::int64_t>(std::ceil(r.y_max / cell));
  TraversabilityGrid out(fixedWindowParams(grid.params(), i0, j0, i1 - i0, j1 - j0));
  for (std::int64_t gj = std::max(j0, grid.originJ()); gj < std::min(j1, grid.originJ() + grid.sizeY()); ++gj) {
    for (std::int64_t gi = std::max(i0, grid.originI()); gi < std::min(i1, grid.originI() + grid.sizeX()); ++gi) {
      out.at(static_cast<int>(gi - i0), static_cast<int>(gj - j0)) =
          grid.at(static_cast<int>(gi - grid.originI()), static_cast<int>(gj - grid.originJ()));
    }
  }
  return out;
}

}  // namespace upd::maps
