// A route to the goal over the fused traversability map, handed to the reactive navigator as
// waypoints.
//
// Why a route at all: MRPT's PTG navigator only steers towards targets inside its PTGs' domain
// (a few metres, the refDistance) and, being reactive, can be trapped in front of a long
// obstacle (the ditch) or a platform whose only access is on its far side (the ramp). A grid
// search over what the map knows resolves both; the navigator still does the driving and the
// obstacle avoidance between waypoints.
//
// The search is the project's one grid planner (upd/maps/grid_planner.h: A*, 8-connected, on
// the grid's cells); this unit prepares its raster. It treats a cell as
//  - blocked when it is NonTraversable (labelOf) or holds a fixed obstacle point, or lies
//    closer than inflation_m to such a cell (the robot's half-width plus a margin);
//  - free otherwise, Unknown cells included (optimistic: unexplored ground may be crossed;
//    the map blocks it as soon as the camera sees an obstacle there), at a cost that grows
//    near obstacles (within clearance_m) and by unknown_cost for Unknown cells, so routes keep
//    to the middle of passages and to mapped ground.
// Cells around the start (within start_free_radius_m) that are blocked only by inflation stay
// passable, so a robot already close to an obstacle can leave it.
#pragma once

#include "upd/core/params.h"

#include <Eigen/Core>

#include <vector>

namespace upd::maps {
class TraversabilityGrid;
}

namespace upd::nav {

/// Loaded from [RoutePlannerParams].
struct RoutePlannerParams {
  double inflation_m = 0.3;          ///< keep the route this far from obstacle cells [m]
  double clearance_m = 0.7;          ///< within this of an obstacle the cost rises [m]
  double clearance_weight = 4.0;     ///< extra cost per cell at the obstacle's edge [-]
  double unknown_cost = 0.5;         ///< extra cost per Unknown cell [-]
  double start_free_radius_m = 0.5;  ///< inflation is ignored this close to the start [m]
  double waypoint_spacing_m = 1.5;   ///< waypoints along the route every this [m]
  double replan_period_s = 1.0;      ///< the route is recomputed this often [s]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("inflation_m", inflation_m, "routes keep this far from obstacle cells [m]");
    v("clearance_m", clearance_m, "the route cost rises within this of obstacles [m]");
    v("clearance_weight", clearance_weight, "extra cost per cell at an obstacle's edge");
    v("unknown_cost", unknown_cost, "extra cost per unknown (unobserved) cell");
    v("start_free_radius_m", start_free_radius_m,
      "inflation is ignored this close to the start [m]");
    v("waypoint_spacing_m", waypoint_spacing_m, "distance between waypoints along the route [m]");
    v("replan_period_s", replan_period_s, "the route is recomputed this often [s]");
  }
};

struct Route {
  bool found = false;
  std::vector<Eigen::Vector2d> path_world;  ///< cell centres from start to goal (world frame)
  std::vector<Eigen::Vector2d> waypoints;   ///< every waypoint_spacing_m; the last is the goal
  double length_m = 0.0;
};

/// Plans from start to goal (world frame) over grid plus the fixed obstacle points. A goal
/// outside the grid's window is replaced by the window cell nearest to it (the route then ends
/// there and the waypoints still end at the goal). Throws std::invalid_argument for bad params.
Route planRoute(const maps::TraversabilityGrid& grid,
                const std::vector<Eigen::Vector2d>& fixed_obstacles_world,
                const Eigen::Vector2d& start_world, const Eigen::Vector2d& goal_world,
                const RoutePlannerParams& params);

}  // namespace upd::nav
