// Properties of the 2.5D traversability grid and its log-odds fusion over frames.
#include "maps/frames.h"
#include "upd/maps/grid_fusion.h"
#include "upd/maps/traversability_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

namespace core = upd::core;

using upd::core::Label;
using upd::maps::FusionParams;
using upd::maps::GridParams;
using upd::maps::integrateScan;
using upd::maps::TraversabilityGrid;
using upd::test::Frame;

namespace {

GridParams smallGrid(bool follow = false) {
  GridParams g;
  g.cell_size_m = 0.1;
  g.extent_m = 10.0;
  g.follow_robot = follow;
  return g;
}

// Centre of world cell (i, j) for 0.1 m cells.
constexpr double kCell = 0.1;
double centre(int i) { return (i + 0.5) * kCell; }

Frame cellFrame(int i, int j, core::Label l, int n = 20) {
  Frame f;
  f.fillCell(i * kCell, j * kCell, kCell, n, l);
  return f;
}

void integrate(TraversabilityGrid& g, const Frame& f, double t = 0.0) {
  integrateScan(g, f.view(), Eigen::Vector2d::Zero(), t, FusionParams{});
}

}  // namespace

TEST(GridFusion, RepeatedEvidenceSharpens) {
  TraversabilityGrid g(smallGrid());
  const Frame rock = cellFrame(12, -7, core::Label::NonTraversable);
  integrate(g, rock);
  const float p1 = upd::maps::probabilityNonTraversable(g, centre(12), centre(-7));
  for (int k = 0; k < 4; ++k) integrate(g, rock);
  const float p5 = upd::maps::probabilityNonTraversable(g, centre(12), centre(-7));
  EXPECT_GT(p1, 0.5f);
  EXPECT_GT(p5, p1);
  EXPECT_NEAR(p1, 1.0 / (1.0 + std::exp(-0.85)), 1e-5);
  EXPECT_NEAR(p5, 1.0 / (1.0 + std::exp(-3.5)), 1e-5);  // clamped at logodds_max
  EXPECT_EQ(upd::maps::cellLabel(g, centre(12), centre(-7)), core::Label::NonTraversable);

  // The same for traversable evidence, towards 0.
  const Frame ground = cellFrame(3, 3, core::Label::Traversable);
  integrate(g, ground);
  const float q1 = upd::maps::probabilityNonTraversable(g, centre(3), centre(3));
  for (int k = 0; k < 4; ++k) integrate(g, ground);
  const float q5 = upd::maps::probabilityNonTraversable(g, centre(3), centre(3));
  EXPECT_LT(q1, 0.5f);
  EXPECT_LT(q5, q1);
  EXPECT_EQ(upd::maps::cellLabel(g, centre(3), centre(3)), core::Label::Traversable);
}

TEST(GridFusion, OneUpdatePerCellPerFrameWhateverThePointCount) {
  TraversabilityGrid dense(smallGrid()), sparse(smallGrid());
  integrate(dense, cellFrame(0, 0, core::Label::NonTraversable, 1000));
  integrate(sparse, cellFrame(0, 0, core::Label::NonTraversable, 1));
  EXPECT_FLOAT_EQ(upd::maps::probabilityNonTraversable(dense, centre(0), centre(0)),
                  upd::maps::probabilityNonTraversable(sparse, centre(0), centre(0)));
  EXPECT_EQ(dense.cellAt(centre(0), centre(0))->hits, 1000u);
}

TEST(GridFusion, ObstaclePersistsWhenUnobservedAndSurvivesOneContradiction) {
  TraversabilityGrid g(smallGrid());
  const Frame rock = cellFrame(5, 5, core::Label::NonTraversable);
  for (int k = 0; k < 5; ++k) integrate(g, rock, k);
  const float seen = upd::maps::probabilityNonTraversable(g, centre(5), centre(5));
  const auto before = *g.cellAt(centre(5), centre(5));

  // Frames that observe only other cells leave it untouched.
  for (int k = 0; k < 10; ++k) integrate(g, cellFrame(-20 + k, 8, core::Label::Traversable), 10 + k);
  EXPECT_FLOAT_EQ(upd::maps::probabilityNonTraversable(g, centre(5), centre(5)), seen);
  EXPECT_EQ(g.cellAt(centre(5), centre(5))->hits, before.hits);
  EXPECT_EQ(g.cellAt(centre(5), centre(5))->last_seen_s, before.last_seen_s);

  // One frame that sees it traversable lowers it, but it stays non-traversable.
  integrate(g, cellFrame(5, 5, core::Label::Traversable), 30);
  const float after = upd::maps::probabilityNonTraversable(g, centre(5), centre(5));
  EXPECT_LT(after, seen);
  EXPECT_EQ(upd::maps::cellLabel(g, centre(5), centre(5)), core::Label::NonTraversable);
}

TEST(GridFusion, FalseAlarmFades) {
  TraversabilityGrid g(smallGrid());
  integrate(g, cellFrame(-3, 4, core::Label::NonTraversable));
  EXPECT_EQ(upd::maps::cellLabel(g, centre(-3), centre(4)), core::Label::NonTraversable);
  int frames = 0;
  while (upd::maps::probabilityNonTraversable(g, centre(-3), centre(4)) >= 0.5f && frames < 20) {
    integrate(g, cellFrame(-3, 4, core::Label::Traversable));
    ++frames;
  }
  EXPECT_EQ(frames, 3);  // 0.85 - 3 * 0.4 < 0
  EXPECT_EQ(upd::maps::cellLabel(g, centre(-3), centre(4)), core::Label::Traversable);
  // The clamp keeps a long-traversable cell revisable: 14 frames later, 5 hits flip it back.
  for (int k = 0; k < 14; ++k) integrate(g, cellFrame(-3, 4, core::Label::Traversable));
  EXPECT_FLOAT_EQ(g.cellAt(centre(-3), centre(4))->logodds_nontrav, -2.0f);
  for (int k = 0; k < 5; ++k) integrate(g, cellFrame(-3, 4, core::Label::NonTraversable));
  EXPECT_EQ(upd::maps::cellLabel(g, centre(-3), centre(4)), core::Label::NonTraversable);
}

TEST(GridFusion, UnseenCellsStayUnknown) {
  TraversabilityGrid g(smallGrid());
  integrate(g, cellFrame(1, 1, core::Label::NonTraversable));
  Frame unknown_only;
  unknown_only.fillCell(2 * kCell, 2 * kCell, kCell, 30, core::Label::Unknown);
  const auto stats = integrateScan(g, unknown_only.view(), {0, 0}, 0, FusionParams{});
  EXPECT_EQ(stats.points_unknown, 30u);
  EXPECT_EQ(stats.cells_updated, 0u);

  for (const auto& [x, y] : std::vector<std::pair<double, double>>{
           {centre(2), centre(2)}, {centre(-40), centre(33)}, {4.95, -4.95}}) {
    EXPECT_TRUE(std::isnan(upd::maps::probabilityNonTraversable(g, x, y)));
    EXPECT_FALSE(upd::maps::isKnown(g, x, y));
    EXPECT_EQ(upd::maps::cellLabel(g, x, y), core::Label::Unknown);
    EXPECT_TRUE(std::isnan(g.cellAt(x, y)->zeta_min));
    EXPECT_EQ(g.cellAt(x, y)->hits, 0u);
  }
  // Outside the window: unknown too, and no cell.
  EXPECT_EQ(g.cellAt(100.0, 0.0), nullptr);
  EXPECT_EQ(upd::maps::cellLabel(g, 100.0, 0.0), core::Label::Unknown);
  EXPECT_TRUE(std::isnan(upd::maps::probabilityNonTraversable(g, NAN, 0.0)));

  const auto s = upd::maps::computeStats(g);
  EXPECT_EQ(s.cells, 100u * 100u);
  EXPECT_EQ(s.known, 1u);
  EXPECT_EQ(s.non_traversable, 1u);
  EXPECT_EQ(s.traversable, 0u);
}

TEST(GridFusion, FractionRuleDecidesHitOrMiss) {
  FusionParams fp;  // nontrav_fraction 0.25
  TraversabilityGrid g(smallGrid());
  Frame f;
  f.fillCell(0, 0, kCell, 2, core::Label::NonTraversable);  // 2 of 10: miss
  f.fillCell(0, 0, kCell, 8, core::Label::Traversable);
  f.fillCell(kCell, 0, kCell, 3, core::Label::NonTraversable);  // 3 of 12: exactly 0.25, hit
  f.fillCell(kCell, 0, kCell, 9, core::Label::Traversable);
  const auto stats = integrateScan(g, f.view(), {0, 0}, 1.0, fp);
  EXPECT_EQ(stats.cells_updated, 2u);
  EXPECT_EQ(stats.cells_hit, 1u);
  EXPECT_EQ(upd::maps::cellLabel(g, centre(0), centre(0)), core::Label::Traversable);
  EXPECT_EQ(upd::maps::cellLabel(g, centre(1), centre(0)), core::Label::NonTraversable);

  EXPECT_DOUBLE_EQ(upd::maps::frameLogOddsUpdate(3, 7, fp), fp.logodds_hit);
  EXPECT_DOUBLE_EQ(upd::maps::frameLogOddsUpdate(2, 8, fp), fp.logodds_miss);
  EXPECT_DOUBLE_EQ(upd::maps::frameLogOddsUpdate(0, 0, fp), 0.0);
  fp.min_points_per_cell = 5;
  EXPECT_DOUBLE_EQ(upd::maps::frameLogOddsUpdate(4, 0, fp), 0.0);
}

TEST(GridFusion, LayersHoldMinMeanMaxHitsAndTime) {
  TraversabilityGrid g(smallGrid());
  Frame a;
  a.add(0.01f, 0.01f, 0.10f, core::Label::Traversable, 0.99f, 0.10f, 0.2f);
  a.add(0.02f, 0.02f, 0.30f, core::Label::NonTraversable, 0.90f, 0.30f, 1.0f);
  integrateScan(g, a.view(), {0, 0}, 5.0, FusionParams{});
  Frame b;
  b.add(0.05f, 0.05f, 0.20f, core::Label::Traversable, 0.97f, 0.20f, NAN);
  b.add(0.06f, 0.06f, 0.20f, core::Label::Unknown, 0.10f, 1.0f, 1.0f);  // ignored entirely
  integrateScan(g, b.view(), {0, 0}, 7.5, FusionParams{});
  const auto* c = g.cellAt(0.05, 0.05);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->hits, 3u);
  EXPECT_FLOAT_EQ(c->zeta_min, 0.90f);
  EXPECT_NEAR(c->zeta_mean, (0.99 + 0.90 + 0.97) / 3, 1e-6);
  EXPECT_NEAR(c->slope_rad, (0.10 + 0.30 + 0.20) / 3, 1e-6);
  EXPECT_NEAR(c->cost_mean, (0.2 + 1.0) / 2, 1e-6);  // NaN cost not counted
  EXPECT_EQ(c->cost_count, 2u);
  EXPECT_NEAR(c->elevation_m, (0.10 + 0.30 + 0.20) / 3, 1e-6);
  EXPECT_FLOAT_EQ(c->elevation_max_m, 0.30f);
  EXPECT_DOUBLE_EQ(c->last_seen_s, 7.5);
  // 1 of 2 non-traversable (hit, +0.85), then 0 of 1 (miss, -0.4).
  EXPECT_NEAR(c->logodds_nontrav, 0.45, 1e-6);

  const Eigen::MatrixXf zmin = upd::maps::layerMatrix(g, upd::maps::GridLayer::ZetaMin);
  int cx, cy;
  ASSERT_TRUE(g.cellIndex(0.05, 0.05, cx, cy));
  EXPECT_FLOAT_EQ(zmin(cy, cx), 0.90f);
  EXPECT_TRUE(std::isnan(zmin(0, 0)));
  EXPECT_STREQ(upd::maps::layerName(upd::maps::GridLayer::ZetaMin), "zeta_min");
}

TEST(GridFusion, InvalidAndOutsidePointsAreCountedNotUsed) {
  TraversabilityGrid g(smallGrid());
  Frame f;
  f.add(NAN, 0.f, 0.f, core::Label::NonTraversable);
  f.add(0.f, INFINITY, 0.f, core::Label::NonTraversable);
  f.add(0.f, 0.f, NAN, core::Label::NonTraversable);
  f.add(50.f, 0.f, 0.f, core::Label::NonTraversable);    // outside the fixed 10 m window
  f.add(-5.01f, 0.f, 0.f, core::Label::NonTraversable);  // just outside the lower edge
  f.add(-4.99f, 0.f, 0.f, core::Label::NonTraversable);  // just inside
  const auto s = integrateScan(g, f.view(), {0, 0}, 0, FusionParams{});
  EXPECT_EQ(s.points_invalid, 3u);
  EXPECT_EQ(s.points_outside, 2u);
  EXPECT_EQ(s.points_used, 1u);
  EXPECT_EQ(s.cells_updated, 1u);
  EXPECT_EQ(upd::maps::computeStats(g).known, 1u);
  EXPECT_EQ(upd::maps::cellLabel(g, -4.99, 0.0), core::Label::NonTraversable);
}

TEST(GridFusion, WindowFollowsTheRobotWithBoundedMemory) {
  GridParams gp;
  gp.cell_size_m = 0.2;
  gp.extent_m = 20.0;
  gp.follow_robot = true;
  gp.keep_outside_window = false;  // the window alone (whole_run_test.cpp: with the tiles)
  TraversabilityGrid g(gp);
  const std::size_t memory0 = g.memoryBytes();
  const std::size_t cells = static_cast<std::size_t>(g.sizeX()) * g.sizeY();
  std::size_t max_known = 0;
  int moves = 0;
  // 1 km along a diagonal, one frame per metre, each a 4 m x 4 m patch ahead of the robot.
  for (int step = 0; step <= 1000; ++step) {
    const double d = step / std::sqrt(2.0);
    Frame f;
    for (int u = 0; u < 18; ++u) {  // up to 4.7 m ahead: inside the window before it moves
      for (int v = 0; v < 20; ++v) {
        f.add(static_cast<float>(d + 1.0 + 0.2 * u + 0.1),
              static_cast<float>(d - 2.0 + 0.2 * v + 0.1), 0.f,
              (u + v) % 9 == 0 ? core::Label::NonTraversable : core::Label::Traversable);
      }
    }
    const auto s = integrateScan(g, f.view(), {d, d}, step, FusionParams{});
    moves += s.window_moved ? 1 : 0;
    EXPECT_EQ(s.points_outside, 0u) << "step " << step;
    EXPECT_EQ(g.memoryBytes(), memory0);
    max_known = std::max(max_known, upd::maps::computeStats(g).known);
  }
  EXPECT_LE(max_known, cells);
  EXPECT_GT(moves, 50);
  // The start scrolled out long ago; the robot's surroundings are in the window and mapped.
  EXPECT_EQ(g.cellAt(1.1, -1.9), nullptr);
  const double d = 1000 / std::sqrt(2.0);
  EXPECT_TRUE(upd::maps::isKnown(g, d + 2.0, d));
  EXPECT_LE(std::abs(d - 0.5 * (g.xMin() + g.xMax())), gp.recenter_fraction * gp.extent_m + 0.2);
}

TEST(GridFusion, RecentringKeepsCellsAtTheirWorldPosition) {
  GridParams gp = smallGrid(true);
  gp.keep_outside_window = false;
  TraversabilityGrid g(gp);
  Frame rock;
  rock.fillCell(3.0, 1.0, kCell, 10, core::Label::NonTraversable);
  for (int k = 0; k < 3; ++k) integrateScan(g, rock.view(), {0, 0}, k, FusionParams{});
  const float p = upd::maps::probabilityNonTraversable(g, 3.05, 1.05);
  const auto before = *g.cellAt(3.05, 1.05);
  EXPECT_FALSE(g.moveTo({2.0, 0.0}));  // inside the central part: no move
  EXPECT_TRUE(g.moveTo({4.0, 2.7}));
  EXPECT_NEAR(0.5 * (g.xMin() + g.xMax()), 4.0, kCell);
  EXPECT_FLOAT_EQ(upd::maps::probabilityNonTraversable(g, 3.05, 1.05), p);
  EXPECT_EQ(g.cellAt(3.05, 1.05)->hits, before.hits);
  EXPECT_FALSE(upd::maps::isKnown(g, 3.15, 1.05));
  EXPECT_FALSE(upd::maps::isKnown(g, 3.05, 0.95));
  int cx, cy;
  ASSERT_TRUE(g.cellIndex(3.05, 1.05, cx, cy));
  EXPECT_NEAR(g.cellCenter(cx, cy).x(), 3.05, 1e-9);
  EXPECT_NEAR(g.cellCenter(cx, cy).y(), 1.05, 1e-9);
}

// The window's place is kept in 64-bit world cell indices: a robot (or a centre) so far out that
// its index would not convert, only ever a corrupt pose, is refused by name, not converted.
TEST(GridFusion, PositionBeyondTheGridsReachIsRefused) {
  GridParams params;
  params.cell_size_m = kCell;
  params.extent_m = 4.0;
  params.follow_robot = true;
  TraversabilityGrid g(params);
  for (const Eigen::Vector2d& far : {Eigen::Vector2d(1e30, 0.0), Eigen::Vector2d(0.0, -2e14),
                                    Eigen::Vector2d(std::nan(""), 0.0)}) {
    try {
      g.moveTo(far);
      ADD_FAILURE() << "moved to " << far.transpose();
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("robot_xy = "), std::string::npos) << e.what();
      EXPECT_LT(std::string(e.what()).size(), 120u) << e.what();
    }
  }
  EXPECT_TRUE(g.moveTo({1e12, -1e12}));  // far, but within reach: the window follows
  EXPECT_NEAR(0.5 * (g.xMin() + g.xMax()), 1e12, 1.0);
  params.center_x_m = 1e300;
  EXPECT_THROW(TraversabilityGrid{params}, std::invalid_argument);
}

TEST(GridFusion, SameResultFarFromTheOrigin) {
  const double offset = 250000.0;  // 250 km: float world coordinates keep ~2 cm here
  GridParams near_p = smallGrid(), far_p = smallGrid();
  far_p.center_x_m = far_p.center_y_m = offset;
  TraversabilityGrid near_g(near_p), far_g(far_p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-4.5f, 4.5f);
  for (int frame = 0; frame < 5; ++frame) {
    Frame a, b;
    for (int k = 0; k < 2000; ++k) {
      // Keep points 1/4 cell away from cell edges so float rounding far out cannot move them.
      const float px = std::floor(pos(rng) / 0.1f) * 0.1f + 0.05f;
      const float py = std::floor(pos(rng) / 0.1f) * 0.1f + 0.05f;
      const core::Label l = (k % 5 == 0) ? core::Label::NonTraversable : core::Label::Traversable;
      a.add(px, py, 0.f, l);
      b.add(static_cast<float>(px + offset), static_cast<float>(py + offset), 0.f, l);
    }
    integrateScan(near_g, a.view(), {0, 0}, frame, FusionParams{});
    integrateScan(far_g, b.view(), {offset, offset}, frame, FusionParams{});
  }
  std::size_t compared = 0;
  upd::maps::forEachKnownCell(near_g, [&](int cx, int cy, const upd::maps::GridCell& n) {
    const Eigen::Vector2d c = near_g.cellCenter(cx, cy);
    const auto* f = far_g.cellAt(c.x() + offset, c.y() + offset);
    ASSERT_NE(f, nullptr);
    EXPECT_EQ(n.hits, f->hits) << cx << "," << cy;
    EXPECT_FLOAT_EQ(n.logodds_nontrav, f->logodds_nontrav);
    ++compared;
  });
  EXPECT_GT(compared, 1000u);
  EXPECT_EQ(upd::maps::computeStats(near_g).known, upd::maps::computeStats(far_g).known);
}

TEST(GridFusion, AgreesWithBruteForcePerCellFusion) {
  TraversabilityGrid g(smallGrid());
  const FusionParams fp;
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> pos(-1.0f, 1.0f);
  std::uniform_int_distribution<int> lab(0, 4);
  std::map<std::pair<int, int>, double> expected;  // brute force: per cell, per frame
  for (int frame = 0; frame < 20; ++frame) {
    Frame f;
    std::map<std::pair<int, int>, std::pair<int, int>> counts;  // nontrav, trav
    for (int k = 0; k < 500; ++k) {
      const float px = pos(rng), py = pos(rng);
      const int r = lab(rng);
      const core::Label l =
          r == 0 ? core::Label::NonTraversable : (r == 4 ? core::Label::Unknown : core::Label::Traversable);
      f.add(px, py, 0.f, l);
      if (l == core::Label::Unknown) continue;
      auto& c =
          counts[{static_cast<int>(std::floor(px / 0.1)), static_cast<int>(std::floor(py / 0.1))}];
      (l == core::Label::NonTraversable ? c.first : c.second)++;
    }
    integrateScan(g, f.view(), {0, 0}, frame, fp);
    for (const auto& [cell, c] : counts) {
      const bool hit = c.first >= fp.nontrav_fraction * (c.first + c.second) - 1e-9;
      double& L = expected.try_emplace(cell, 0.0).first->second;
      L = std::clamp(L + (hit ? fp.logodds_hit : fp.logodds_miss), fp.logodds_min, fp.logodds_max);
    }
  }
  for (const auto& [cell, L] : expected) {
    const auto* c = g.cellAt(centre(cell.first), centre(cell.second));
    ASSERT_NE(c, nullptr);
    EXPECT_NEAR(c->logodds_nontrav, L, 1e-5) << cell.first << "," << cell.second;
  }
  EXPECT_EQ(upd::maps::computeStats(g).known, expected.size());
}

TEST(GridFusion, ParametersAreValidatedWithTheFieldName) {
  GridParams gp;
  gp.cell_size_m = 0;
  try {
    TraversabilityGrid g(gp);
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("GridParams.cell_size_m = 0"), std::string::npos)
        << e.what();
  }
  FusionParams fp;
  fp.logodds_miss = 0.3;
  TraversabilityGrid g(smallGrid());
  Frame f = cellFrame(0, 0, core::Label::Traversable);
  EXPECT_THROW(integrateScan(g, f.view(), {0, 0}, 0, fp), std::invalid_argument);
  upd::maps::PointsWorld bad = f.view();
  bad.label = nullptr;
  EXPECT_THROW(integrateScan(g, bad, {0, 0}, 0, FusionParams{}), std::invalid_argument);
  EXPECT_THROW(integrateScan(g, f.view(), {0, 0}, NAN, FusionParams{}), std::invalid_argument);
}

TEST(GridFusion, ViewsPipelineArraysWithoutCopying) {
  upd::core::PointCloud cloud;
  cloud.push_back(0.05f, 0.05f, 0.f);
  cloud.push_back(0.15f, 0.05f, 0.f);
  upd::core::Classification cls;
  cls.label = {core::Label::NonTraversable, core::Label::Traversable};
  cls.cost = {1.f, 0.f};
  cls.slope_rad = {0.5f, 0.f};
  upd::core::UpdResult upd_res;
  upd_res.zeta = {0.8f, 1.f};
  const auto v = upd::maps::viewPoints(cloud, cls, &upd_res);
  EXPECT_EQ(v.x, cloud.x.data());
  EXPECT_EQ(v.label, cls.label.data());
  EXPECT_EQ(v.zeta, upd_res.zeta.data());
  TraversabilityGrid g(smallGrid());
  integrateScan(g, v, {0, 0}, 0, FusionParams{});
  EXPECT_EQ(upd::maps::cellLabel(g, 0.05, 0.05), core::Label::NonTraversable);
  EXPECT_FLOAT_EQ(g.cellAt(0.05, 0.05)->zeta_min, 0.8f);
  cls.label.pop_back();
  EXPECT_THROW(upd::maps::viewPoints(cloud, cls), std::invalid_argument);
}
