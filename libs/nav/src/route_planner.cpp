#include "upd/nav/route_planner.h"

#include "upd/maps/traversability_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <stdexcept>

namespace upd::nav {

void RoutePlannerParams::validate() const {
  const auto nonneg = [](double v) { return std::isfinite(v) && v >= 0; };
  requireParam(nonneg(inflation_m), "RoutePlannerParams", "inflation_m", inflation_m,
               "must be >= 0");
  requireParam(nonneg(clearance_m), "RoutePlannerParams", "clearance_m", clearance_m,
               "must be >= 0");
  requireParam(nonneg(clearance_weight), "RoutePlannerParams", "clearance_weight", clearance_weight,
               "must be >= 0");
  requireParam(nonneg(unknown_cost), "RoutePlannerParams", "unknown_cost", unknown_cost,
               "must be >= 0");
  requireParam(nonneg(start_free_radius_m), "RoutePlannerParams", "start_free_radius_m",
               start_free_radius_m, "must be >= 0");
  requireParam(std::isfinite(waypoint_spacing_m) && waypoint_spacing_m > 0, "RoutePlannerParams",
               "waypoint_spacing_m", waypoint_spacing_m, "must be > 0");
  requireParam(std::isfinite(replan_period_s) && replan_period_s > 0, "RoutePlannerParams",
               "replan_period_s", replan_period_s, "must be > 0");
}

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Waypoints every spacing along the polyline, ending exactly at goal.
std::vector<Eigen::Vector2d> sampleWaypoints(const std::vector<Eigen::Vector2d>& path,
                                             const Eigen::Vector2d& goal, double spacing) {
  std::vector<Eigen::Vector2d> wps;
  double since = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) {
    Eigen::Vector2d a = path[i - 1];
    const Eigen::Vector2d b = path[i];
    double seg = (b - a).norm();
    while (since + seg >= spacing) {
      const double t = (spacing - since) / seg;
      a = a + t * (b - a);
      wps.push_back(a);
      seg = (b - a).norm();
      since = 0.0;
    }
    since += seg;
  }
  // The goal replaces a waypoint that would sit right before it.
  while (!wps.empty() && (wps.back() - goal).norm() < 0.5 * spacing) wps.pop_back();
  wps.push_back(goal);
  return wps;
}

}  // namespace

Route planRoute(const maps::TraversabilityGrid& grid,
                const std::vector<Eigen::Vector2d>& fixed_obstacles_world,
                const Eigen::Vector2d& start_world, const Eigen::Vector2d& goal_world,
                const RoutePlannerParams& params) {
  params.validate();
  if (!start_world.allFinite() || !goal_world.allFinite()) {
    throw std::invalid_argument("planRoute: start and goal must be finite");
  }
  const int nx = grid.sizeX(), ny = grid.sizeY();
  const double cell = grid.cellSize();
  const auto idx = [nx](int cx, int cy) { return static_cast<std::size_t>(cy) * nx + cx; };
  const std::size_t n = static_cast<std::size_t>(nx) * ny;

  // Hard obstacles: NonTraversable cells and fixed points.
  std::vector<std::uint8_t> hard(n, 0), unknown(n, 0);
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      const Label l = maps::labelOf(grid.at(cx, cy), grid.params());
      hard[idx(cx, cy)] = l == Label::NonTraversable;
      unknown[idx(cx, cy)] = l == Label::Unknown;
    }
  }
  for (const auto& p : fixed_obstacles_world) {
    int cx, cy;
    if (grid.cellIndex(p.x(), p.y(), cx, cy)) hard[idx(cx, cy)] = 1;
  }

  // Distance from each cell centre to the nearest hard cell centre, up to the larger of the
  // inflation and clearance radii (stamped discs; farther cells stay at +inf).
  const double reach_m = std::max(params.inflation_m, params.clearance_m);
  const int r_cells = static_cast<int>(std::ceil(reach_m / cell));
  std::vector<float> dist(n, kInf);
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      if (!hard[idx(cx, cy)]) continue;
      for (int dy = -r_cells; dy <= r_cells; ++dy) {
        const int y = cy + dy;
        if (y < 0 || y >= ny) continue;
        for (int dx = -r_cells; dx <= r_cells; ++dx) {
          const int x = cx + dx;
          if (x < 0 || x >= nx) continue;
          const float d = static_cast<float>(cell * std::sqrt(double(dx * dx + dy * dy)));
          float& cur = dist[idx(x, y)];
          cur = std::min(cur, d);
        }
      }
    }
  }

  const auto clampCell = [&](const Eigen::Vector2d& p, int& cx, int& cy) {
    const double x = std::clamp(p.x(), grid.xMin() + 0.5 * cell, grid.xMax() - 0.5 * cell);
    const double y = std::clamp(p.y(), grid.yMin() + 0.5 * cell, grid.yMax() - 0.5 * cell);
    return grid.cellIndex(x, y, cx, cy);
  };
  int sx, sy, gx, gy;
  Route route;
  if (!clampCell(start_world, sx, sy) || !clampCell(goal_world, gx, gy)) return route;

  const double start_free2 = params.start_free_radius_m * params.start_free_radius_m;
  const auto passable = [&](int cx, int cy) {
    const std::size_t i = idx(cx, cy);
    if (hard[i]) return false;
    if (dist[i] >= params.inflation_m) return true;
    const Eigen::Vector2d c = grid.cellCenter(cx, cy);
    return (c - start_world).squaredNorm() <= start_free2;
  };
  const auto cellCost = [&](std::size_t i) {
    double c = 1.0;
    if (params.clearance_m > 0 && dist[i] < params.clearance_m) {
      const double t = 1.0 - dist[i] / params.clearance_m;
      c += params.clearance_weight * t * t;
    }
    if (unknown[i]) c += params.unknown_cost;
    return c;
  };
  if (!passable(gx, gy)) return route;

  // A* with the Euclidean distance (in cells) as the admissible heuristic (every cost >= 1).
  std::vector<double> g(n, std::numeric_limits<double>::infinity());
  std::vector<std::int32_t> parent(n, -1);
  std::vector<std::uint8_t> closed(n, 0);
  using Entry = std::pair<double, std::int32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  const auto h = [&](int cx, int cy) { return std::hypot(double(cx - gx), double(cy - gy)); };
  const std::size_t s = idx(sx, sy), goal_i = idx(gx, gy);
  g[s] = 0.0;
  open.emplace(h(sx, sy), static_cast<std::int32_t>(s));
  static const int kDx[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  static const int kDy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  while (!open.empty()) {
    const auto [f, ci] = open.top();
    open.pop();
    const auto cur = static_cast<std::size_t>(ci);
    if (closed[cur]) continue;
    closed[cur] = 1;
    if (cur == goal_i) break;
    const int cx = static_cast<int>(cur % nx), cy = static_cast<int>(cur / nx);
    for (int k = 0; k < 8; ++k) {
      const int x = cx + kDx[k], y = cy + kDy[k];
      if (x < 0 || y < 0 || x >= nx || y >= ny || !passable(x, y)) continue;
      // No corner cutting between two blocked cells.
      if (k >= 4 && (!passable(cx + kDx[k], cy) || !passable(cx, cy + kDy[k]))) continue;
      const std::size_t ni = idx(x, y);
      if (closed[ni]) continue;
      const double step = (k >= 4 ? std::sqrt(2.0) : 1.0) * 0.5 * (cellCost(cur) + cellCost(ni));
      if (g[cur] + step < g[ni]) {
        g[ni] = g[cur] + step;
        parent[ni] = static_cast<std::int32_t>(cur);
        open.emplace(g[ni] + h(x, y), static_cast<std::int32_t>(ni));
      }
    }
  }
  if (!closed[goal_i]) return route;

  for (std::int64_t i = static_cast<std::int64_t>(goal_i); i >= 0; i = parent[i]) {
    const int cx = static_cast<int>(i % nx), cy = static_cast<int>(i / nx);
    route.path_world.push_back(grid.cellCenter(cx, cy));
    if (static_cast<std::size_t>(i) == s) break;
  }
  std::reverse(route.path_world.begin(), route.path_world.end());
  route.path_world.front() = start_world;
  route.path_world.push_back(goal_world);
  for (std::size_t i = 1; i < route.path_world.size(); ++i) {
    route.length_m += (route.path_world[i] - route.path_world[i - 1]).norm();
  }
  route.waypoints = sampleWaypoints(route.path_world, goal_world, params.waypoint_spacing_m);
  route.found = true;
  return route;
}

}  // namespace upd::nav
