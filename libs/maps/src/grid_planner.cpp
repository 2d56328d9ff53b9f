#include "upd/maps/grid_planner.h"

#include "upd/core/params.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>

namespace upd::maps {

void GridPlannerParams::validate() const {
  const auto nonneg = [](double v) { return std::isfinite(v) && v >= 0; };
  core::requireParam(nonneg(inflation_m), "GridPlannerParams", "inflation_m", inflation_m,
               "must be >= 0");
  core::requireParam(nonneg(clearance_m), "GridPlannerParams", "clearance_m", clearance_m,
               "must be >= 0");
  core::requireParam(nonneg(clearance_weight), "GridPlannerParams", "clearance_weight", clearance_weight,
               "must be >= 0");
}

namespace {

void checkView(const PlannerGridView& g) {
  if (g.width < 0 || g.height < 0 || !(g.cell_m > 0) || !std::isfinite(g.cell_m) ||
      (g.blocked == nullptr && g.width * g.height > 0)) {
    throw std::invalid_argument("PlannerGridView: " + std::to_string(g.width) + " x " +
                                std::to_string(g.height) + " cells of " + std::to_string(g.cell_m) +
                                " m: needs sizes >= 0, cell_m > 0 and a blocked buffer");
  }
}

// The cells the search may enter (see the header comment).
std::vector<std::uint8_t> passableCells(const PlannerGridView& g, const std::vector<float>& dist,
                                        double inflation_m) {
  std::vector<std::uint8_t> passable(dist.size(), 0);
  for (std::size_t i = 0; i < passable.size(); ++i) {
    if (g.blocked[i]) continue;
    passable[i] = dist[i] >= inflation_m || (g.inflation_exempt && g.inflation_exempt[i]);
  }
  return passable;
}

// The cost of entering each cell: 1, more near blocked cells, plus the caller's extra.
std::vector<double> cellCosts(const PlannerGridView& g, const std::vector<float>& dist,
                              const GridPlannerParams& p) {
  std::vector<double> cost(dist.size(), 1.0);
  for (std::size_t i = 0; i < cost.size(); ++i) {
    double c = 1.0;
    if (p.clearance_m > 0 && dist[i] < p.clearance_m) {
      const double t = 1.0 - dist[i] / p.clearance_m;
      c += p.clearance_weight * t * t;
    }
    if (g.extra_cost) c += g.extra_cost[i];
    cost[i] = c;
  }
  return cost;
}

// The A* search proper on prepared passability and costs; parents per cell (-1: none).
std::vector<std::int32_t> searchParents(const PlannerGridView& g, const GridPlan& plan,
                                        const std::vector<double>& cost, std::size_t s,
                                        std::size_t goal_i, std::vector<double>& g_cost) {
  const int nx = g.width;
  const int gx = static_cast<int>(goal_i % nx), gy = static_cast<int>(goal_i / nx);
  const auto passable = [&](int x, int y) { return plan.passable[g.index(x, y)] != 0; };
  const auto h = [&](int cx, int cy) { return std::hypot(double(cx - gx), double(cy - gy)); };
  g_cost.assign(plan.passable.size(), std::numeric_limits<double>::infinity());
  std::vector<std::int32_t> parent(plan.passable.size(), -1);
  std::vector<std::uint8_t> closed(plan.passable.size(), 0);
  using Entry = std::pair<double, std::int32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  g_cost[s] = 0.0;
  open.emplace(h(static_cast<int>(s % nx), static_cast<int>(s / nx)), static_cast<std::int32_t>(s));
  static const int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static const int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  while (!open.empty()) {
    const auto cur = static_cast<std::size_t>(open.top().second);
    open.pop();
    if (closed[cur]) continue;
    closed[cur] = 1;
    if (cur == goal_i) break;
    const int cx = static_cast<int>(cur % nx), cy = static_cast<int>(cur / nx);
    for (int k = 0; k < 8; ++k) {
      const int x = cx + kDx[k], y = cy + kDy[k];
      if (!g.inside(x, y) || !passable(x, y)) continue;
      // No corner cutting between two impassable cells.
      if (k >= 4 && (!passable(cx + kDx[k], cy) || !passable(cx, cy + kDy[k]))) continue;
      const std::size_t ni = g.index(x, y);
      if (closed[ni]) continue;
      const double step = (k >= 4 ? std::sqrt(2.0) : 1.0) * 0.5 * (cost[cur] + cost[ni]);
      if (g_cost[cur] + step < g_cost[ni]) {
        g_cost[ni] = g_cost[cur] + step;
        parent[ni] = static_cast<std::int32_t>(cur);
        open.emplace(g_cost[ni] + h(x, y), static_cast<std::int32_t>(ni));
      }
    }
  }
  if (!closed[goal_i]) parent.clear();
  return parent;
}

}  // namespace

std::vector<float> distanceToBlocked(const PlannerGridView& g, double reach_m) {
  checkView(g);
  const int nx = g.width, ny = g.height;
  const int r_cells = static_cast<int>(std::ceil(reach_m / g.cell_m));
  std::vector<float> dist(static_cast<std::size_t>(nx) * ny,
                          std::numeric_limits<float>::infinity());
  // Stamped discs: exact Euclidean distances between cell centres within the reach.
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      if (!g.blocked[g.index(cx, cy)]) continue;
      for (int dy = -r_cells; dy <= r_cells; ++dy) {
        const int y = cy + dy;
        if (y < 0 || y >= ny) continue;
        for (int dx = -r_cells; dx <= r_cells; ++dx) {
          const int x = cx + dx;
          if (x < 0 || x >= nx) continue;
          const float d = static_cast<float>(g.cell_m * std::sqrt(double(dx * dx + dy * dy)));
          float& cur = dist[g.index(x, y)];
          cur = std::min(cur, d);
        }
      }
    }
  }
  return dist;
}

GridPlan planGridPath(const PlannerGridView& g, const Eigen::Vector2i& start,
                      const Eigen::Vector2i& goal, const GridPlannerParams& params) {
  params.validate();
  GridPlan plan;
  plan.distance_m = distanceToBlocked(g, std::max(params.inflation_m, params.clearance_m));
  plan.passable = passableCells(g, plan.distance_m, params.inflation_m);
  if (!g.inside(start.x(), start.y()) || !g.inside(goal.x(), goal.y()) ||
      !plan.passable[g.index(goal.x(), goal.y())]) {
    return plan;
  }
  const std::vector<double> cost = cellCosts(g, plan.distance_m, params);
  const std::size_t s = g.index(start.x(), start.y()), goal_i = g.index(goal.x(), goal.y());
  std::vector<double> g_cost;
  const std::vector<std::int32_t> parent = searchParents(g, plan, cost, s, goal_i, g_cost);
  if (parent.empty()) return plan;
  for (std::int64_t i = static_cast<std::int64_t>(goal_i); i >= 0; i = parent[i]) {
    plan.cells.emplace_back(static_cast<int>(i % g.width), static_cast<int>(i / g.width));
    if (static_cast<std::size_t>(i) == s) break;
  }
  std::reverse(plan.cells.begin(), plan.cells.end());
  plan.cost = g_cost[goal_i];
  plan.found = true;
  return plan;
}

std::vector<Eigen::Vector2d> shortcutPath(const PlannerGridView& g,
                                          const std::vector<std::uint8_t>& passable,
                                          const Eigen::Vector2d& origin_xy,
                                          const std::vector<Eigen::Vector2d>& pts) {
  if (pts.size() < 3) return pts;
  const auto free = [&](const Eigen::Vector2d& p) {
    const int i = static_cast<int>(std::floor((p.x() - origin_xy.x()) / g.cell_m));
    const int j = static_cast<int>(std::floor((p.y() - origin_xy.y()) / g.cell_m));
    return g.inside(i, j) && passable[g.index(i, j)] != 0;
  };
  const auto lineFree = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    const int steps = static_cast<int>(std::ceil((b - a).norm() / (0.25 * g.cell_m))) + 1;
    for (int s = 0; s <= steps; ++s) {
      if (!free(a + (b - a) * (double(s) / steps))) return false;
    }
    return true;
  };
  std::vector<Eigen::Vector2d> path{pts.front()};
  std::size_t k = 0;
  while (k + 1 < pts.size()) {
    std::size_t far = k + 1;
    for (std::size_t m = pts.size() - 1; m > k + 1; --m) {
      if (lineFree(pts[k], pts[m])) {
        far = m;
        break;
      }
    }
    path.push_back(pts[far]);
    k = far;
  }
  return path;
}

}  // namespace upd::maps
