#include "upd/maps/grid_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

namespace upd::maps {

namespace {

// One frame's points in one cell.
struct FrameCell {
  std::uint32_t n_nontrav = 0, n_trav = 0;
  float zeta_min = std::numeric_limits<float>::quiet_NaN();
  double zeta_sum = 0, slope_sum = 0, cost_sum = 0, z_sum = 0;
  std::uint32_t n_zeta = 0, n_slope = 0, n_cost = 0;
  float z_max = -std::numeric_limits<float>::infinity();
};

bool finiteValue(const float* values, std::size_t i, float& v) {
  if (values == nullptr) return false;
  v = values[i];
  return std::isfinite(v);
}

// Running mean over old_count earlier samples and n new ones summing to sum.
float mergeMean(float mean, std::uint32_t old_count, double sum, std::uint32_t n) {
  if (n == 0) return mean;
  if (old_count == 0) return static_cast<float>(sum / n);
  return static_cast<float>((static_cast<double>(mean) * old_count + sum) /
                            (static_cast<double>(old_count) + n));
}

std::uint32_t addSaturating(std::uint32_t a, std::uint32_t b) {
  const std::uint64_t s = static_cast<std::uint64_t>(a) + b;
  return static_cast<std::uint32_t>(
      std::min<std::uint64_t>(s, std::numeric_limits<std::uint32_t>::max()));
}

}  // namespace

GridFusionStats integrateScan(TraversabilityGrid& grid, const PointsWorld& points,
                              const Eigen::Vector2d& robot_xy, double time_s,
                              const FusionParams& params) {
  params.validate();
  points.validate();
  requireParam(std::isfinite(time_s), "integrateScan", "time_s", time_s, "must be finite");
  GridFusionStats stats;
  stats.window_moved = grid.moveTo(robot_xy);

  // Aggregate first: one log-odds update per cell per frame, whatever its point count.
  const int size_x = grid.sizeX();
  std::unordered_map<std::uint32_t, FrameCell> frame;
  frame.reserve(
      std::min<std::size_t>(points.size / 4 + 16, static_cast<std::size_t>(size_x) * grid.sizeY()));
  for (std::size_t i = 0; i < points.size; ++i) {
    const float x = points.x[i], y = points.y[i], z = points.z[i];
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      ++stats.points_invalid;
      continue;
    }
    const Label label = points.label[i];
    if (label != Label::Traversable && label != Label::NonTraversable) {
      ++stats.points_unknown;
      continue;
    }
    int cx, cy;
    if (!grid.cellIndex(x, y, cx, cy)) {
      ++stats.points_outside;
      continue;
    }
    ++stats.points_used;
    FrameCell& f = frame[static_cast<std::uint32_t>(cy) * static_cast<std::uint32_t>(size_x) +
                         static_cast<std::uint32_t>(cx)];
    if (label == Label::NonTraversable) {
      ++f.n_nontrav;
    } else {
      ++f.n_trav;
    }
    f.z_sum += z;
    f.z_max = std::max(f.z_max, z);
    float v;
    if (finiteValue(points.zeta, i, v)) {
      f.zeta_min = std::fmin(f.zeta_min, v);
      f.zeta_sum += v;
      ++f.n_zeta;
    }
    if (finiteValue(points.slope_rad, i, v)) {
      f.slope_sum += v;
      ++f.n_slope;
    }
    if (finiteValue(points.cost, i, v)) {
      f.cost_sum += v;
      ++f.n_cost;
    }
  }

  for (const auto& [index, f] : frame) {
    const double update = frameLogOddsUpdate(f.n_nontrav, f.n_trav, params);
    if (update == 0.0) {
      ++stats.cells_too_sparse;
      continue;
    }
    GridCell& c = grid.at(static_cast<int>(index % static_cast<std::uint32_t>(size_x)),
                          static_cast<int>(index / static_cast<std::uint32_t>(size_x)));
    c.logodds_nontrav = fuseLogOdds(c.logodds_nontrav, update, params);
    ++stats.cells_updated;
    if (update > 0) ++stats.cells_hit;

    const std::uint32_t n = f.n_nontrav + f.n_trav;
    c.elevation_m = mergeMean(c.elevation_m, c.hits, f.z_sum, n);
    c.elevation_max_m = std::fmax(c.elevation_max_m, f.z_max);
    c.zeta_min = std::fmin(c.zeta_min, f.zeta_min);
    c.zeta_mean = mergeMean(c.zeta_mean, c.zeta_count, f.zeta_sum, f.n_zeta);
    c.slope_rad = mergeMean(c.slope_rad, c.slope_count, f.slope_sum, f.n_slope);
    c.cost_mean = mergeMean(c.cost_mean, c.cost_count, f.cost_sum, f.n_cost);
    c.hits = addSaturating(c.hits, n);
    c.zeta_count = addSaturating(c.zeta_count, f.n_zeta);
    c.slope_count = addSaturating(c.slope_count, f.n_slope);
    c.cost_count = addSaturating(c.cost_count, f.n_cost);
    c.last_seen_s = time_s;
  }
  return stats;
}

}  // namespace upd::maps
