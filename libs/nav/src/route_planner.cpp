#include "upd/nav/route_planner.h"

#include "upd/maps/grid_planner.h"
#include "upd/maps/traversability_grid.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace upd::nav {

void RoutePlannerParams::validate() const {
  const auto nonneg = [](double v) { return std::isfinite(v) && v >= 0; };
  core::requireParam(nonneg(inflation_m), "RoutePlannerParams", "inflation_m", inflation_m,
               "must be >= 0");
  core::requireParam(nonneg(clearance_m), "RoutePlannerParams", "clearance_m", clearance_m,
               "must be >= 0");
  core::requireParam(nonneg(clearance_weight), "RoutePlannerParams", "clearance_weight", clearance_weight,
               "must be >= 0");
  core::requireParam(nonneg(unknown_cost), "RoutePlannerParams", "unknown_cost", unknown_cost,
               "must be >= 0");
  core::requireParam(nonneg(start_free_radius_m), "RoutePlannerParams", "start_free_radius_m",
               start_free_radius_m, "must be >= 0");
  core::requireParam(std::isfinite(waypoint_spacing_m) && waypoint_spacing_m > 0, "RoutePlannerParams",
               "waypoint_spacing_m", waypoint_spacing_m, "must be > 0");
  core::requireParam(std::isfinite(replan_period_s) && replan_period_s > 0, "RoutePlannerParams",
               "replan_period_s", replan_period_s, "must be > 0");
}

namespace {

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

namespace {

// The planner's raster over the grid's window: hard obstacles (NonTraversable cells and fixed
// points), the cells around the start exempt from inflation, and the extra cost of Unknown cells.
struct RouteRaster {
  std::vector<std::uint8_t> blocked, exempt;
  std::vector<double> extra_cost;
  maps::PlannerGridView view;
};

RouteRaster rasterize(const maps::TraversabilityGrid& grid,
                      const std::vector<Eigen::Vector2d>& fixed_obstacles_world,
                      const Eigen::Vector2d& start_world, const RoutePlannerParams& params) {
  const int nx = grid.sizeX(), ny = grid.sizeY();
  const std::size_t n = static_cast<std::size_t>(nx) * ny;
  RouteRaster r;
  r.blocked.assign(n, 0);
  r.exempt.assign(n, 0);
  r.extra_cost.assign(n, 0.0);
  const double start_free2 = params.start_free_radius_m * params.start_free_radius_m;
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      const std::size_t i = static_cast<std::size_t>(cy) * nx + cx;
      const core::Label l = maps::labelOf(grid.at(cx, cy), grid.params());
      r.blocked[i] = l == core::Label::NonTraversable;
      if (l == core::Label::Unknown) r.extra_cost[i] = params.unknown_cost;
      r.exempt[i] = (grid.cellCenter(cx, cy) - start_world).squaredNorm() <= start_free2;
    }
  }
  for (const auto& p : fixed_obstacles_world) {
    int cx, cy;
    if (grid.cellIndex(p.x(), p.y(), cx, cy)) r.blocked[static_cast<std::size_t>(cy) * nx + cx] = 1;
  }
  r.view.width = nx;
  r.view.height = ny;
  r.view.cell_m = grid.cellSize();
  r.view.blocked = r.blocked.data();
  r.view.inflation_exempt = r.exempt.data();
  r.view.extra_cost = r.extra_cost.data();
  return r;
}

// The cell of p, clamped into the grid's window; false when the grid has no cells.
bool clampedCell(const maps::TraversabilityGrid& grid, const Eigen::Vector2d& p,
                 Eigen::Vector2i& cell) {
  const double half = 0.5 * grid.cellSize();
  const double x = std::clamp(p.x(), grid.xMin() + half, grid.xMax() - half);
  const double y = std::clamp(p.y(), grid.yMin() + half, grid.yMax() - half);
  return grid.cellIndex(x, y, cell.x(), cell.y());
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
  Route route;
  Eigen::Vector2i start_cell, goal_cell;
  if (!clampedCell(grid, start_world, start_cell) || !clampedCell(grid, goal_world, goal_cell)) {
    return route;
  }
  const RouteRaster raster = rasterize(grid, fixed_obstacles_world, start_world, params);
  maps::GridPlannerParams gp;
  gp.inflation_m = params.inflation_m;
  gp.clearance_m = params.clearance_m;
  gp.clearance_weight = params.clearance_weight;
  const maps::GridPlan plan = maps::planGridPath(raster.view, start_cell, goal_cell, gp);
  if (!plan.found) return route;

  for (const Eigen::Vector2i& c : plan.cells) {
    route.path_world.push_back(grid.cellCenter(c.x(), c.y()));
  }
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
