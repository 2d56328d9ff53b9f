// The navigation benchmark's pieces that need no closed loop: generated worlds are solvable on
// the ground truth for the robot's footprint (the optimal path keeps its clearance and joins
// start and goal; hard ones keep the wider margin the navigator needs, which leaves the easy and
// default worlds as they are), the summary's figures, worlds.csv read back as written, and the comparison
// that the CI regression runs.
#include "upd/nav/bench.h"

#include "upd/maps/grid_planner.h"
#include "upd/sim/truth_raster.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

namespace upd::nav {
namespace {

namespace fs = std::filesystem;

// Distance from p to the nearest NonTraversable truth cell centre (up to 2 m).
double distanceToObstacle(const sim::TruthRaster& t, const Eigen::Vector2d& p) {
  double best = 2.0;
  for (int iy = 0; iy < t.sizeY(); ++iy) {
    for (int ix = 0; ix < t.sizeX(); ++ix) {
      if (t.at(ix, iy) != core::Label::NonTraversable) continue;
      best = std::min(best, (t.cellCenter(ix, iy) - p).norm());
    }
  }
  return best;
}

TEST(NavBench, GeneratedWorldsAreSolvableForTheFootprint) {
  const sim::RobotBodyParams body;
  const BenchParams params;
  for (sim::Difficulty d : {sim::Difficulty::Easy, sim::Difficulty::Default, sim::Difficulty::Hard}) {
    for (int seed = 1; seed <= 3; ++seed) {
      sim::WorldGenParams gen;
      gen.seed = seed;
      gen.difficulty = d;
      const BenchWorld w = makeBenchWorld(gen, body, params);
      const sim::WorldSpec& spec = w.generated.world;
      ASSERT_GE(w.optimal_path.size(), 2u);
      EXPECT_LT((w.optimal_path.front() - spec.start_xy_yaw.head<2>()).norm(), 1e-6);
      EXPECT_LT((w.optimal_path.back() - spec.goal_xy).norm(), 1e-6);
      EXPECT_GE(w.optimal_path_m, gen.goal_distance_m - 1e-6);
      // Every point along the optimal path keeps half the width from non-traversable truth
      // (less the planner's 0.1 m cells).
      const sim::TruthRaster truth(spec.terrain, 0.05);
      for (std::size_t i = 1; i < w.optimal_path.size(); ++i) {
        const Eigen::Vector2d a = w.optimal_path[i - 1], b = w.optimal_path[i];
        for (double t = 0; t <= 1.0; t += 0.1 / std::max(0.1, (b - a).norm())) {
          ASSERT_GT(distanceToObstacle(truth, a + t * (b - a)), 0.5 * body.width_m - 0.1)
              << sim::toString(d) << " seed " << seed;
        }
      }
    }
  }
}

// True when a way joins start and goal on the truth (0.1 m cells, the border closed) keeping
// clearance_m from every cell that is not traversable.
bool wayWithClearance(const sim::WorldSpec& world, double clearance_m) {
  const sim::TruthRaster truth(world.terrain, 0.1);
  std::vector<std::uint8_t> blocked(static_cast<std::size_t>(truth.sizeX()) * truth.sizeY());
  for (int iy = 0; iy < truth.sizeY(); ++iy) {
    for (int ix = 0; ix < truth.sizeX(); ++ix) {
      const bool border = ix == 0 || iy == 0 || ix == truth.sizeX() - 1 || iy == truth.sizeY() - 1;
      blocked[static_cast<std::size_t>(iy) * truth.sizeX() + ix] =
          border || truth.at(ix, iy) != core::Label::Traversable;
    }
  }
  maps::PlannerGridView view;
  view.width = truth.sizeX();
  view.height = truth.sizeY();
  view.cell_m = 0.1;
  view.blocked = blocked.data();
  const auto cell = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2d c = (p - truth.origin()) / 0.1;
    return Eigen::Vector2i(static_cast<int>(std::floor(c.x())), static_cast<int>(std::floor(c.y())));
  };
  maps::GridPlannerParams gp;
  gp.inflation_m = clearance_m;
  return maps::planGridPath(view, cell(world.start_xy_yaw.head<2>()), cell(world.goal_xy), gp).found;
}

// Each difficulty's worlds are checked solvable with its own clearance (sim::solvableClearance):
// hard worlds keep 0.2 m beyond the half-width on their way (about their narrowest wall gap;
// with the others' 0.1 m, seeds 1-3 had passages of 0.8 m between obstacles, in which the
// oracle's robot circled until the time limit). BenchParams::footprint_margin_m overrides it.
TEST(NavBench, EachDifficultyIsCheckedWithItsOwnClearance) {
  EXPECT_EQ(sim::solvableClearance(sim::Difficulty::Easy), 0.1);
  EXPECT_EQ(sim::solvableClearance(sim::Difficulty::Default), 0.1);
  EXPECT_EQ(sim::solvableClearance(sim::Difficulty::Hard), 0.2);
  const sim::RobotBodyParams body;
  const BenchParams params;
  for (sim::Difficulty d : {sim::Difficulty::Easy, sim::Difficulty::Default, sim::Difficulty::Hard}) {
    BenchParams same = params;
    same.footprint_margin_m = sim::solvableClearance(d);
    for (int seed = 1; seed <= 3; ++seed) {
      sim::WorldGenParams gen;
      gen.seed = seed;
      gen.difficulty = d;
      const BenchWorld a = makeBenchWorld(gen, body, params), b = makeBenchWorld(gen, body, same);
      EXPECT_EQ(a.generated.attempts, b.generated.attempts);
      EXPECT_EQ(a.generated.world.description, b.generated.world.description);
      EXPECT_EQ(a.optimal_path_m, b.optimal_path_m) << sim::toString(d) << " seed " << seed;
      if (d == sim::Difficulty::Hard) {
        EXPECT_TRUE(wayWithClearance(a.generated.world, 0.5 * body.width_m + 0.2))
            << "hard seed " << seed;
      }
    }
  }
  // The override is the check's clearance: 3 m beyond the half-width fits through no wall gap
  // (at most 2 m wide), so no candidate of a hard world passes.
  BenchParams wide = params;
  wide.footprint_margin_m = 3.0;
  sim::WorldGenParams gen;
  gen.difficulty = sim::Difficulty::Hard;
  gen.max_attempts = 3;
  EXPECT_THROW(makeBenchWorld(gen, body, wide), std::runtime_error);
}

// A stop on an open map is the navigator's unless the planner had given up at the end: plans
// that failed on the way do not make it a planning failure; a map with no way is a false
// obstacle.
TEST(NavBench, StopCategoryReflectsThePlannerAtTheEnd) {
  sim::WorldSpec world{sim::Terrain({-5.0, -5.0}, {5.0, 5.0}), {-3.0, 0.0, 0.0}, {3.0, 0.0}, ""};
  const NavConfig config;
  ScenarioResult run;
  run.trajectory.push_back({});
  run.trajectory.back().pose_world_robot = {-3.0, 0.0, 0.0};
  run.failed_plans = 12;  // earlier plans failed, the map is open now (unknown cells are free)
  run.replanning_stopped = false;
  EXPECT_EQ(categorize(run, world, config, BenchOutcome::Stuck), FailureCause::Navigator);
  run.replanning_stopped = true;
  EXPECT_EQ(categorize(run, world, config, BenchOutcome::Stuck), FailureCause::Planning);
  // A mapped wall across the whole world between robot and goal: no way on the map.
  for (double y = -5.0; y <= 5.0; y += 0.05) {
    maps::GridCell* c = run.grid.cellAt(0.0, y);
    ASSERT_NE(c, nullptr);
    c->hits = 10;
    c->logodds_nontrav = 3.0f;
  }
  EXPECT_EQ(categorize(run, world, config, BenchOutcome::Stuck), FailureCause::FalseObstacle);
  EXPECT_EQ(categorize(run, world, config, BenchOutcome::Success), FailureCause::None);
}

BenchRow row(int seed, BenchOutcome o, double time_ratio, FailureCause c = FailureCause::None) {
  BenchRow r;
  r.seed = seed;
  r.difficulty = "default";
  r.obstacles = "upd";
  r.outcome = o;
  r.cause = c;
  r.time_s = 25.0 * time_ratio;
  r.optimal_time_s = 25.0;
  r.time_ratio = time_ratio;
  r.path_ratio = 1.1;
  r.min_clearance_m = 0.1 * seed;
  r.end = "goal reached";
  return r;
}

TEST(NavBench, SummaryCountsOutcomesAndAveragesTheSuccesses) {
  const std::vector<BenchRow> rows = {
      row(1, BenchOutcome::Success, 1.2), row(2, BenchOutcome::Success, 1.4),
      row(3, BenchOutcome::Collision, 0.5, FailureCause::MissedObstacle),
      row(4, BenchOutcome::Stuck, 2.0, FailureCause::FalseObstacle)};
  const nlohmann::json s = benchSummary(rows);
  EXPECT_EQ(s["worlds"], 4);
  EXPECT_DOUBLE_EQ(s["success_rate"].get<double>(), 0.5);
  EXPECT_EQ(s["collisions"], 1);
  EXPECT_EQ(s["stuck"], 1);
  EXPECT_EQ(s["timeouts"], 0);
  EXPECT_NEAR(s["time_ratio"].get<double>(), 1.3, 1e-12);
  EXPECT_NEAR(s["min_clearance_m"].get<double>(), 0.1, 1e-12);
  EXPECT_EQ(s["failures"]["missed_obstacle"], 1);
  EXPECT_EQ(s["failures"]["false_obstacle"], 1);
}

TEST(NavBench, CsvReadsBackAndTheComparisonFindsRegressions) {
  const fs::path p = fs::temp_directory_path() / ("upd_bench_" + std::to_string(::getpid()) + ".csv");
  const std::vector<BenchRow> rows = {row(1, BenchOutcome::Success, 1.2),
                                      row(2, BenchOutcome::Timeout, 2.4, FailureCause::Planning)};
  writeBenchCsv(p.string(), rows);
  const std::vector<BenchRow> back = readBenchCsv(p.string());
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].outcome, BenchOutcome::Timeout);
  EXPECT_EQ(back[1].cause, FailureCause::Planning);
  EXPECT_NEAR(back[0].time_ratio, 1.2, 1e-3);
  EXPECT_TRUE(compareBench(rows, back, 0.01).empty());

  std::vector<BenchRow> worse = back;
  worse[0].time_ratio = 1.6;
  EXPECT_EQ(compareBench(rows, worse, 0.25).size(), 1u);   // slower beyond the tolerance
  EXPECT_TRUE(compareBench(rows, worse, 0.5).empty());
  worse[1].outcome = BenchOutcome::Collision;
  EXPECT_EQ(compareBench(rows, worse, 0.5).size(), 1u);    // another outcome
  EXPECT_EQ(compareBench(rows, {back[0]}, 0.5).size(), 1u);  // a world not run

  std::ofstream(p) << "seed,oops\n1,2\n";
  EXPECT_THROW(readBenchCsv(p.string()), std::runtime_error);
  fs::remove(p);
  EXPECT_THROW(parseBenchPerception("lidar"), std::invalid_argument);
}

}  // namespace
}  // namespace upd::nav
