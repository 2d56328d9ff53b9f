#include "upd/maps/grid_fusion.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#ifdef _OPENMP
#include <omp.h>
#endif

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
  // 1. The cell of every point (in parallel), or why it has none.
  constexpr std::uint32_t kInvalid = 0xFFFFFFFFu, kUnknown = 0xFFFFFFFEu, kOutside = 0xFFFFFFFDu;
  const int size_x = grid.sizeX();
  const std::size_t n_cells = static_cast<std::size_t>(size_x) * grid.sizeY();
  const GridCellIndexer cell_index = grid.indexer();  // inline: no call per point
  static thread_local std::vector<std::uint32_t> point_cell;
  point_cell.resize(points.size);
  std::uint32_t* const cell_of = point_cell.data();  // the calling thread's, shared by the team
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(points.size); ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const float x = points.x[i], y = points.y[i], z = points.z[i];
    std::uint32_t code;
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      code = kInvalid;
    } else if (points.label[i] != Label::Traversable && points.label[i] != Label::NonTraversable) {
      code = kUnknown;
    } else if (int cx, cy; cell_index(x, y, cx, cy)) {
      code = static_cast<std::uint32_t>(cy) * static_cast<std::uint32_t>(size_x) +
             static_cast<std::uint32_t>(cx);
    } else {
      code = kOutside;
    }
    cell_of[i] = code;
  }
  // 2. Per-frame sums per touched cell, then one update per cell. The grid's rows are dealt to
  // the threads in bands: every thread reads all the points and takes those of its bands,
  // in point order, so the result does not depend on the number of threads. A dense slot table
  // over the grid (per thread, reset after use) points each touched cell to its FrameCell;
  // consecutive points mostly share a cell.
  std::size_t invalid = 0, unknown = 0, outside = 0, used = 0, updated = 0, hit = 0, sparse = 0;
#pragma omp parallel reduction(+ : invalid, unknown, outside, used, updated, hit, sparse)
  {
#ifdef _OPENMP
    const int team = omp_get_num_threads(), me = omp_get_thread_num();
#else
    const int team = 1, me = 0;
#endif
    static thread_local std::vector<std::uint32_t> slot_of_cell;
    if (slot_of_cell.size() < n_cells) slot_of_cell.assign(n_cells, kInvalid);
    std::uint32_t* const slots = slot_of_cell.data();
    std::vector<FrameCell> frame;
    std::vector<std::uint32_t> frame_index;
    std::uint32_t last_cell = kInvalid;
    bool mine = false;
    FrameCell* cur = nullptr;
    for (std::size_t i = 0; i < points.size; ++i) {
      const std::uint32_t cell = cell_of[i];
      if (cell >= kOutside) {
        if (me == 0) {  // counted once
          invalid += cell == kInvalid ? 1 : 0;
          unknown += cell == kUnknown ? 1 : 0;
          outside += cell == kOutside ? 1 : 0;
        }
        continue;
      }
      if (cell != last_cell) {
        // Bands of 8 rows, dealt round-robin: a view covers a few bands, not half the grid.
        last_cell = cell;
        mine = static_cast<int>((cell / static_cast<std::uint32_t>(size_x)) / 8) % team == me;
        if (mine) {
          std::uint32_t& slot = slots[cell];
          if (slot == kInvalid) {
            slot = static_cast<std::uint32_t>(frame.size());
            frame.emplace_back();
            frame_index.push_back(cell);
          }
          cur = &frame[slot];
        }
      }
      if (!mine) continue;
      ++used;
      if (points.label[i] == Label::NonTraversable) {
        ++cur->n_nontrav;
      } else {
        ++cur->n_trav;
      }
      const float z = points.z[i];
      cur->z_sum += z;
      cur->z_max = std::max(cur->z_max, z);
      float v;
      if (finiteValue(points.zeta, i, v)) {
        cur->zeta_min = cur->zeta_min <= v ? cur->zeta_min : v;  // NaN (none yet) takes v
        cur->zeta_sum += v;
        ++cur->n_zeta;
      }
      if (finiteValue(points.slope_rad, i, v)) {
        cur->slope_sum += v;
        ++cur->n_slope;
      }
      if (finiteValue(points.cost, i, v)) {
        cur->cost_sum += v;
        ++cur->n_cost;
      }
    }
    for (const std::uint32_t cell : frame_index) slots[cell] = kInvalid;

    for (std::size_t s = 0; s < frame.size(); ++s) {
      const std::uint32_t index = frame_index[s];
      const FrameCell& f = frame[s];
      const double update = frameLogOddsUpdate(f.n_nontrav, f.n_trav, params);
      if (update == 0.0) {
        ++sparse;
        continue;
      }
      GridCell& c = grid.at(static_cast<int>(index % static_cast<std::uint32_t>(size_x)),
                            static_cast<int>(index / static_cast<std::uint32_t>(size_x)));
      c.logodds_nontrav = fuseLogOdds(c.logodds_nontrav, update, params);
      ++updated;
      if (update > 0) ++hit;

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
  }
  stats.points_invalid = invalid;
  stats.points_unknown = unknown;
  stats.points_outside = outside;
  stats.points_used = used;
  stats.cells_updated = updated;
  stats.cells_hit = hit;
  stats.cells_too_sparse = sparse;
  return stats;
}

}  // namespace upd::maps
