// The grid planner against brute force on small random rasters (the same reachability and the
// same optimal cost as an exhaustive Dijkstra; exact distances to blocked cells), and its
// properties: paths keep the inflation from blocked cells, the clearance cost pulls them to
// the middle of a passage, the exempt cells let a robot leave an obstacle, shortcutPath keeps
// to passable cells.
#include "upd/maps/grid_planner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace upd::maps {
namespace {

struct Raster {
  int w, h;
  std::vector<std::uint8_t> blocked;
  PlannerGridView view(double cell_m = 1.0) const {
    PlannerGridView v;
    v.width = w;
    v.height = h;
    v.cell_m = cell_m;
    v.blocked = blocked.data();
    return v;
  }
};

Raster randomRaster(int w, int h, double fill, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution b(fill);
  Raster r{w, h, std::vector<std::uint8_t>(static_cast<std::size_t>(w) * h)};
  for (auto& c : r.blocked) c = b(rng);
  return r;
}

// Exhaustive Dijkstra (Bellman-Ford style relaxation until nothing changes) over the same moves:
// 8-connected, no corner cutting, unit cost per cell (step length in cells).
double bruteForceCost(const Raster& r, const std::vector<std::uint8_t>& passable, Eigen::Vector2i s,
                      Eigen::Vector2i g) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> d(passable.size(), inf);
  const auto at = [&](int x, int y) { return static_cast<std::size_t>(y) * r.w + x; };
  const auto ok = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < r.w && y < r.h && passable[at(x, y)];
  };
  d[at(s.x(), s.y())] = 0;
  for (bool changed = true; changed;) {
    changed = false;
    for (int y = 0; y < r.h; ++y) {
      for (int x = 0; x < r.w; ++x) {
        if (!std::isfinite(d[at(x, y)])) continue;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            if ((!dx && !dy) || !ok(x + dx, y + dy)) continue;
            if (dx && dy && (!ok(x + dx, y) || !ok(x, y + dy))) continue;
            const double c = d[at(x, y)] + std::hypot(dx, dy);
            if (c < d[at(x + dx, y + dy)] - 1e-12) {
              d[at(x + dx, y + dy)] = c;
              changed = true;
            }
          }
        }
      }
    }
  }
  return d[at(g.x(), g.y())];
}

TEST(GridPlanner, DistancesAreExactUpToTheReach) {
  const Raster r = randomRaster(17, 13, 0.08, 3);
  const std::vector<float> d = distanceToBlocked(r.view(0.1), 0.45);
  for (int y = 0; y < r.h; ++y) {
    for (int x = 0; x < r.w; ++x) {
      double best = std::numeric_limits<double>::infinity();
      for (int by = 0; by < r.h; ++by) {
        for (int bx = 0; bx < r.w; ++bx) {
          if (r.blocked[static_cast<std::size_t>(by) * r.w + bx]) {
            best = std::min(best, 0.1 * std::hypot(bx - x, by - y));
          }
        }
      }
      const float got = d[static_cast<std::size_t>(y) * r.w + x];
      if (best <= 0.45 + 1e-9) {
        EXPECT_NEAR(got, best, 1e-6) << x << ", " << y;
      } else {
        EXPECT_TRUE(got > 0.45f) << x << ", " << y;  // beyond the reach: +inf or a far disc edge
      }
    }
  }
}

TEST(GridPlanner, AgreesWithBruteForceOnRandomRasters) {
  int found = 0, not_found = 0;
  for (std::uint32_t seed = 1; seed <= 60; ++seed) {
    const Raster r = randomRaster(12, 9, 0.25, seed);
    GridPlannerParams p;
    p.inflation_m = seed % 3 == 0 ? 1.2 : 0.0;  // orthogonal neighbours of blocked cells too
    const Eigen::Vector2i s(0, seed % 9), g(11, (seed * 5) % 9);
    const GridPlan plan = planGridPath(r.view(), s, g, p);
    const double brute = plan.passable[static_cast<std::size_t>(g.y()) * r.w + g.x()]
                             ? bruteForceCost(r, plan.passable, s, g)
                             : std::numeric_limits<double>::infinity();
    SCOPED_TRACE(seed);
    ASSERT_EQ(plan.found, std::isfinite(brute));
    if (!plan.found) {
      ++not_found;
      continue;
    }
    ++found;
    EXPECT_NEAR(plan.cost, brute, 1e-9);
    ASSERT_EQ(plan.cells.front(), s);
    ASSERT_EQ(plan.cells.back(), g);
    double length = 0;
    for (std::size_t i = 1; i < plan.cells.size(); ++i) {
      const Eigen::Vector2i d = plan.cells[i] - plan.cells[i - 1];
      ASSERT_LE(d.cwiseAbs().maxCoeff(), 1);
      length += std::hypot(d.x(), d.y());
      EXPECT_TRUE(
          plan.passable[static_cast<std::size_t>(plan.cells[i].y()) * r.w + plan.cells[i].x()]);
    }
    EXPECT_NEAR(length, plan.cost, 1e-9);  // unit cells: the cost is the length
  }
  EXPECT_GT(found, 10);
  EXPECT_GT(not_found, 3);
}

TEST(GridPlanner, PathKeepsTheInflationFromBlockedCells) {
  // A wall across x = 20 with a 9-cell gap at y 14..22 (0.1 m cells).
  Raster r{40, 30, std::vector<std::uint8_t>(40 * 30, 0)};
  for (int y = 0; y < r.h; ++y) {
    if (y < 14 || y > 22) r.blocked[static_cast<std::size_t>(y) * r.w + 20] = 1;
  }
  GridPlannerParams p;
  p.inflation_m = 0.3;
  const GridPlan plan = planGridPath(r.view(0.1), {2, 3}, {37, 3}, p);
  ASSERT_TRUE(plan.found);
  for (const auto& c : plan.cells) {
    for (int y = 0; y < r.h; ++y) {
      if (r.blocked[static_cast<std::size_t>(y) * r.w + 20]) {
        EXPECT_GE(0.1 * std::hypot(c.x() - 20, c.y() - y), 0.3 - 1e-9);
      }
    }
  }
  // The gap's middle cell is 0.5 m from both sides: a larger inflation closes it.
  p.inflation_m = 0.5;
  EXPECT_TRUE(planGridPath(r.view(0.1), {2, 3}, {37, 3}, p).found);
  p.inflation_m = 0.55;
  EXPECT_FALSE(planGridPath(r.view(0.1), {2, 3}, {37, 3}, p).found);
}

TEST(GridPlanner, ClearanceCostKeepsToTheMiddleOfAPassage) {
  // A corridor of free rows 1..9 between two blocked rows; the goal and start near one wall.
  Raster r{40, 11, std::vector<std::uint8_t>(40 * 11, 0)};
  for (int x = 0; x < r.w; ++x) {
    r.blocked[static_cast<std::size_t>(x)] = 1;
    r.blocked[static_cast<std::size_t>(10) * r.w + x] = 1;
  }
  GridPlannerParams p;
  p.inflation_m = 0.1;
  const GridPlan hugging = planGridPath(r.view(0.1), {1, 2}, {38, 2}, p);
  p.clearance_m = 0.5;
  p.clearance_weight = 4.0;
  const GridPlan centred = planGridPath(r.view(0.1), {1, 2}, {38, 2}, p);
  ASSERT_TRUE(hugging.found && centred.found);
  int max_hug = 0, max_centred = 0;
  for (const auto& c : hugging.cells) max_hug = std::max(max_hug, c.y());
  for (const auto& c : centred.cells) max_centred = std::max(max_centred, c.y());
  EXPECT_EQ(max_hug, 2);      // straight along the wall
  EXPECT_GE(max_centred, 4);  // away from it in the middle
}

TEST(GridPlanner, ExemptCellsLetTheRobotLeaveAnObstacle) {
  Raster r{20, 20, std::vector<std::uint8_t>(400, 0)};
  r.blocked[static_cast<std::size_t>(5) * 20 + 4] = 1;  // right beside the start (5, 5)
  GridPlannerParams p;
  p.inflation_m = 0.25;
  PlannerGridView v = r.view(0.1);
  EXPECT_FALSE(planGridPath(v, {5, 5}, {15, 15}, p).passable[5 * 20 + 5]);
  std::vector<std::uint8_t> exempt(400, 0);
  exempt[5 * 20 + 5] = exempt[5 * 20 + 6] = exempt[6 * 20 + 6] = 1;
  v.inflation_exempt = exempt.data();
  const GridPlan plan = planGridPath(v, {5, 5}, {15, 15}, p);
  EXPECT_TRUE(plan.found);
  EXPECT_FALSE(plan.passable[5 * 20 + 4]);  // a blocked cell is never exempt
}

TEST(GridPlanner, GoalOutsideOrBlockedIsNotFoundAndBadParamsThrow) {
  const Raster r{5, 5, std::vector<std::uint8_t>(25, 0)};
  EXPECT_FALSE(planGridPath(r.view(), {0, 0}, {7, 0}, GridPlannerParams{0, 0, 0}).found);
  Raster b = r;
  b.blocked[24] = 1;
  EXPECT_FALSE(planGridPath(b.view(), {0, 0}, {4, 4}, GridPlannerParams{0, 0, 0}).found);
  GridPlannerParams bad;
  bad.inflation_m = -1;
  EXPECT_THROW(planGridPath(r.view(), {0, 0}, {4, 4}, bad), std::invalid_argument);
  PlannerGridView nobuf = r.view();
  nobuf.blocked = nullptr;
  EXPECT_THROW(planGridPath(nobuf, {0, 0}, {4, 4}, GridPlannerParams{}), std::invalid_argument);
}

TEST(GridPlanner, ShortcutKeepsEndpointsAndPassableSegments) {
  Raster r{40, 30, std::vector<std::uint8_t>(40 * 30, 0)};
  for (int y = 0; y < 22; ++y) r.blocked[static_cast<std::size_t>(y) * r.w + 20] = 1;
  GridPlannerParams p;
  p.inflation_m = 0.2;
  const PlannerGridView v = r.view(0.1);
  const GridPlan plan = planGridPath(v, {2, 3}, {37, 3}, p);
  ASSERT_TRUE(plan.found);
  std::vector<Eigen::Vector2d> pts;
  for (const auto& c : plan.cells) pts.emplace_back((c.x() + 0.5) * 0.1, (c.y() + 0.5) * 0.1);
  const auto straight = shortcutPath(v, plan.passable, Eigen::Vector2d::Zero(), pts);
  ASSERT_GE(straight.size(), 3u);  // it must bend round the wall
  EXPECT_LT(straight.size(), pts.size() / 4);
  EXPECT_EQ(straight.front(), pts.front());
  EXPECT_EQ(straight.back(), pts.back());
  // Every point of the segments stays near passable cells: at least the inflation less half a
  // cell's diagonal and the quarter-cell sampling from the wall's cell centres.
  for (std::size_t i = 1; i < straight.size(); ++i) {
    for (int s = 0; s <= 100; ++s) {
      const Eigen::Vector2d q = straight[i - 1] + (straight[i] - straight[i - 1]) * (s / 100.0);
      for (int y = 0; y < 22; ++y) {
        ASSERT_GE((q - Eigen::Vector2d(2.05, (y + 0.5) * 0.1)).norm(), 0.2 - 0.071 - 0.025)
            << q.transpose();
      }
    }
  }
}

}  // namespace
}  // namespace upd::maps
