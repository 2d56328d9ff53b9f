// The route planner on hand-made maps: a free field, a wall with a gap, a walled-in goal.
#include "upd/maps/grid_fusion.h"
#include "upd/nav/route_planner.h"

#include <gtest/gtest.h>

#include <cmath>

namespace core = upd::core;

namespace upd::nav {
namespace {

class NavRouteMap : public ::testing::Test {
 protected:
  NavRouteMap() : grid_(params()) {}
  static maps::GridParams params() {
    maps::GridParams gp;
    gp.cell_size_m = 0.1;
    gp.extent_m = 12.0;
    gp.follow_robot = false;
    return gp;
  }
  // Marks every cell whose centre satisfies pred as NonTraversable (and the rest of the
  // rectangle [-5, 5]^2 as Traversable), in one fused frame.
  template <class Pred>
  void paint(Pred pred) {
    std::vector<float> x, y, z;
    std::vector<core::Label> l;
    for (double cx = -4.95; cx < 5.0; cx += 0.1) {
      for (double cy = -4.95; cy < 5.0; cy += 0.1) {
        x.push_back(static_cast<float>(cx));
        y.push_back(static_cast<float>(cy));
        z.push_back(0.f);
        l.push_back(pred(cx, cy) ? core::Label::NonTraversable : core::Label::Traversable);
      }
    }
    maps::PointsWorld v;
    v.x = x.data();
    v.y = y.data();
    v.z = z.data();
    v.label = l.data();
    v.size = x.size();
    maps::integrateScan(grid_, v, {0, 0}, 0.0, maps::FusionParams{});
  }
  // Smallest distance from the route's cells to the cells pred marks.
  template <class Pred>
  static double clearance(const Route& r, Pred pred) {
    double best = 1e9;
    for (const auto& p : r.path_world) {
      for (double cx = -4.95; cx < 5.0; cx += 0.1) {
        for (double cy = -4.95; cy < 5.0; cy += 0.1) {
          if (pred(cx, cy)) best = std::min(best, std::hypot(p.x() - cx, p.y() - cy));
        }
      }
    }
    return best;
  }
  maps::TraversabilityGrid grid_;
};

TEST_F(NavRouteMap, FreeFieldGivesAStraightRouteEndingAtTheGoal) {
  paint([](double, double) { return false; });
  RoutePlannerParams p;
  const Route r = planRoute(grid_, {}, {-3.0, 0.0}, {3.0, 0.0}, p);
  ASSERT_TRUE(r.found);
  EXPECT_NEAR(r.length_m, 6.0, 0.15);
  ASSERT_FALSE(r.waypoints.empty());
  EXPECT_NEAR((r.waypoints.back() - Eigen::Vector2d(3.0, 0.0)).norm(), 0.0, 1e-12);
  // Waypoints every waypoint_spacing_m, the last one possibly closer.
  Eigen::Vector2d prev(-3.0, 0.0);
  for (const auto& w : r.waypoints) {
    EXPECT_LE((w - prev).norm(), p.waypoint_spacing_m + 0.15);
    prev = w;
  }
}

TEST_F(NavRouteMap, RouteTakesTheGapWithClearance) {
  // A wall along x = 0 with a 1.2 m gap at y in [1.5, 2.7].
  const auto wall = [](double x, double y) { return std::abs(x) < 0.1 && !(y > 1.5 && y < 2.7); };
  paint(wall);
  RoutePlannerParams p;
  const Route r = planRoute(grid_, {}, {-3.0, 0.0}, {3.0, 0.0}, p);
  ASSERT_TRUE(r.found);
  bool through_gap = false;
  for (const auto& q : r.path_world)
    through_gap |= std::abs(q.x()) < 0.1 && q.y() > 1.5 && q.y() < 2.7;
  EXPECT_TRUE(through_gap);
  EXPECT_GE(clearance(r, wall), p.inflation_m - 1e-9);
}

TEST_F(NavRouteMap, WalledInGoalHasNoRoute) {
  const auto box = [](double x, double y) {
    const double m = std::max(std::abs(x - 2.0), std::abs(y));
    return m > 0.9 && m < 1.1;
  };
  paint(box);
  const Route r = planRoute(grid_, {}, {-3.0, 0.0}, {2.0, 0.0}, RoutePlannerParams{});
  EXPECT_FALSE(r.found);
  EXPECT_TRUE(r.waypoints.empty());
}

TEST_F(NavRouteMap, FixedObstaclesBlockLikeMapCells) {
  paint([](double, double) { return false; });
  std::vector<Eigen::Vector2d> fence;
  for (double y = -6; y <= 6; y += 0.05) fence.emplace_back(0.0, y);
  EXPECT_FALSE(planRoute(grid_, fence, {-3.0, 0.0}, {3.0, 0.0}, RoutePlannerParams{}).found);
}

TEST_F(NavRouteMap, UnknownGroundIsCrossable) {
  // Nothing observed at all: the route goes straight (optimistic planning).
  const Route r = planRoute(grid_, {}, {-3.0, 0.0}, {3.0, 0.0}, RoutePlannerParams{});
  ASSERT_TRUE(r.found);
  EXPECT_NEAR(r.length_m, 6.0, 0.15);
}

TEST_F(NavRouteMap, BadParamsAreRejected) {
  RoutePlannerParams p;
  p.waypoint_spacing_m = 0.0;
  EXPECT_THROW(planRoute(grid_, {}, {0, 0}, {1, 1}, p), std::invalid_argument);
  EXPECT_THROW(planRoute(grid_, {}, {NAN, 0}, {1, 1}, RoutePlannerParams{}), std::invalid_argument);
}

}  // namespace
}  // namespace upd::nav
