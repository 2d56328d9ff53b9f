// The benchmark's world generator: a seed always gives the same world, different seeds give
// different ones, every world holds the features its difficulty asks for (rocks and steps on
// both sides of the step limit, passages down to the robot's width plus a margin), start and
// goal sit at the set distance on clear ground, and a failing check draws a new candidate.
#include "upd/sim/truth_raster.h"
#include "upd/sim/world_generator.h"

#include <gtest/gtest.h>

#include <cmath>

namespace upd::sim {
namespace {

GeneratedWorld make(int seed, Difficulty d, const SolvableCheck& check = {}) {
  WorldGenParams p;
  p.seed = seed;
  p.difficulty = d;
  return generateWorld(p, check);
}

// The height field sampled on a grid: equal for equal worlds.
std::vector<double> heights(const Terrain& t) {
  std::vector<double> h;
  for (double x = t.minXY().x(); x <= t.maxXY().x(); x += 0.1) {
    for (double y = t.minXY().y(); y <= t.maxXY().y(); y += 0.1) h.push_back(t.heightAt(x, y));
  }
  return h;
}

TEST(SimWorldGenerator, ASeedAlwaysGivesTheSameWorld) {
  for (Difficulty d : {Difficulty::Easy, Difficulty::Default, Difficulty::Hard}) {
    const GeneratedWorld a = make(7, d), b = make(7, d);
    EXPECT_EQ(heights(a.world.terrain), heights(b.world.terrain));
    EXPECT_EQ(a.world.start_xy_yaw, b.world.start_xy_yaw);
    EXPECT_EQ(a.world.goal_xy, b.world.goal_xy);
    EXPECT_EQ(a.world.description, b.world.description);
    const GeneratedWorld c = make(8, d);
    EXPECT_NE(heights(a.world.terrain), heights(c.world.terrain)) << toString(d);
  }
}

TEST(SimWorldGenerator, WorldsHoldTheRequestedFeatures) {
  int drivable_rocks = 0, drivable_steps = 0, steep_ramps = 0, gentle_ramps = 0;
  double narrowest_hard = 10.0;
  for (int seed = 0; seed < 20; ++seed) {
    const WorldFeatures e = make(seed, Difficulty::Easy).features;
    const WorldFeatures m = make(seed, Difficulty::Default).features;
    const GeneratedWorld hard = make(seed, Difficulty::Hard);
    const WorldFeatures& h = hard.features;
    EXPECT_EQ(e.rocks, 5);
    EXPECT_EQ(m.rocks, 8);
    EXPECT_EQ(h.rocks, 12);
    EXPECT_EQ(e.passages, 0);
    EXPECT_EQ(m.passages, 1);
    EXPECT_EQ(h.passages, 2);
    EXPECT_EQ(m.ditches, 1);
    EXPECT_EQ(h.ditches, 2);
    EXPECT_EQ(h.ramps, 2);
    EXPECT_EQ(h.steps, 2);
    EXPECT_GT(h.roughness_rms_m, m.roughness_rms_m);
    EXPECT_GE(m.narrowest_passage_m, 1.3);
    EXPECT_LE(m.narrowest_passage_m, 2.4);
    // The terrain holds what the counts say (a ramp bump is two ramps).
    EXPECT_EQ(hard.world.terrain.rocks().size(), 12u);
    EXPECT_EQ(hard.world.terrain.ramps().size(), 4u);
    EXPECT_EQ(hard.world.terrain.ditches().size(), 2u);
    EXPECT_EQ(hard.world.terrain.boxes().size(), 2u + 2u * 2u);  // steps + two walls a passage
    drivable_rocks += h.rocks_drivable;
    drivable_steps += m.steps_drivable + h.steps_drivable;
    steep_ramps += h.ramps_too_steep;
    gentle_ramps += h.ramps - h.ramps_too_steep;
    narrowest_hard = std::min(narrowest_hard, h.narrowest_passage_m);
  }
  // Rocks and steps on both sides of the step limit, ramps on both sides of the slope limit.
  EXPECT_GT(drivable_rocks, 0);
  EXPECT_GT(drivable_steps, 0);
  EXPECT_GT(steep_ramps, 0);
  EXPECT_GT(gentle_ramps, 0);
  // Hard passages go down to the robot's width plus half a metre.
  EXPECT_LT(narrowest_hard, 1.2);
  EXPECT_GE(narrowest_hard, WorldGenParams{}.robot_width_m + 0.5);
}

TEST(SimWorldGenerator, StartAndGoalAtTheSetDistanceOnClearGround) {
  for (int seed = 0; seed < 10; ++seed) {
    WorldGenParams p;
    p.seed = seed;
    p.difficulty = Difficulty::Hard;
    p.goal_distance_m = 8.0;
    const GeneratedWorld g = generateWorld(p, {});
    const WorldSpec& w = g.world;
    const Eigen::Vector2d start = w.start_xy_yaw.head<2>();
    EXPECT_NEAR((w.goal_xy - start).norm(), 8.0, 1e-9);
    // The robot faces the goal.
    EXPECT_NEAR(w.start_xy_yaw.z(), std::atan2(w.goal_xy.y() - start.y(), w.goal_xy.x() - start.x()),
                1e-9);
    for (const Eigen::Vector2d& q : {start, w.goal_xy}) {
      for (double a = 0; a < 6.28; a += 0.5) {
        const Eigen::Vector2d s = q + 0.8 * Eigen::Vector2d(std::cos(a), std::sin(a));
        EXPECT_EQ(w.terrain.truthAt(s.x(), s.y()), core::Label::Traversable) << seed;
      }
    }
  }
}

TEST(SimWorldGenerator, AFailingCheckDrawsTheNextCandidate) {
  int calls = 0;
  const auto second = [&](const WorldSpec&) { return ++calls >= 2; };
  const GeneratedWorld g = make(3, Difficulty::Default, second);
  EXPECT_EQ(g.attempts, 2);
  // The same seed with the same check gives the same world again.
  calls = 0;
  EXPECT_EQ(heights(make(3, Difficulty::Default, second).world.terrain), heights(g.world.terrain));
  const auto never = [](const WorldSpec&) { return false; };
  EXPECT_THROW(make(3, Difficulty::Default, never), std::runtime_error);
}

TEST(SimWorldGenerator, BadParametersAreRefused) {
  WorldGenParams p;
  p.goal_distance_m = 2.0;
  EXPECT_THROW(generateWorld(p, {}), std::invalid_argument);
  p = WorldGenParams{};
  p.seed = -1;
  EXPECT_THROW(generateWorld(p, {}), std::invalid_argument);
  EXPECT_THROW(parseDifficulty("medium"), std::invalid_argument);
  EXPECT_EQ(parseDifficulty("hard"), Difficulty::Hard);
}

}  // namespace
}  // namespace upd::sim
