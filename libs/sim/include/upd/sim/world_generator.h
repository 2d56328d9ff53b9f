// Procedurally generated worlds for the navigation benchmark (`upd bench-nav`): one world per
// seed, at a difficulty, in the manner of BARN (the Benchmark for Autonomous Robot Navigation:
// many generated worlds, success and time against an optimal path).
//
// A world is goal_distance_m + 4 m long and 8 m wide (x along the way from start to goal, which
// lie 2 m from the ends, up to 1.5 m off the middle line, goal_distance_m apart). Between them
// it holds, each drawn at random (counts and ranges per difficulty in kindsOf()):
//  - rocks from below the truth's step limit (0.05 m: driven over) to well above it;
//  - ramp bumps: a ramp up, a flat top and a ramp down, of a random slope on both sides of the
//    truth's 25 deg limit (traversable or an obstacle);
//  - steps: low platforms, a step up and a step down, some of them below the step limit;
//  - ditches (never traversable);
//  - walls across the whole width with one gap, a narrow passage whose width goes down to the
//    robot's width plus a margin at the hard difficulty;
//  - uneven ground (Roughness).
// Features lie within 2 m of the straight line from start to goal (in the way), none within
// clear_radius_m of the start or the goal.
//
// Solvable by construction: a candidate world is handed to the caller's check (a planner over
// the ground truth with the robot's footprint, upd/nav/bench.h); when it fails, the next
// candidate is drawn from the same seed, so the world of a seed is always the same.
#pragma once

#include "upd/sim/terrain.h"

#include <functional>
#include <string>

namespace upd::sim {

enum class Difficulty { Easy, Default, Hard };
/// "easy", "default" or "hard".
const char* toString(Difficulty d);
/// "easy", "default" or "hard"; throws std::invalid_argument naming the valid values otherwise.
Difficulty parseDifficulty(const std::string& name);

struct WorldGenParams {
  int seed = 1;                             ///< >= 0: the world of a seed never changes
  Difficulty difficulty = Difficulty::Default;
  double goal_distance_m = 10.0;            ///< straight-line start to goal [m], >= 4
  double clear_radius_m = 1.2;              ///< no feature this close to start or goal [m]
  double robot_width_m = 0.45;              ///< the narrowest passage is this plus a margin [m]
  int max_attempts = 50;                    ///< candidates tried before giving up, >= 1

  void validate() const;  ///< std::invalid_argument naming the field
};

/// What a generated world holds, counted by kind (for tests and reports).
struct WorldFeatures {
  int rocks = 0, rocks_drivable = 0;      ///< all rocks; those no taller than max_step_m
  int ramps = 0, ramps_too_steep = 0;     ///< ramp bumps; those steeper than max_slope_rad
  int steps = 0, steps_drivable = 0;      ///< platforms; those no taller than max_step_m
  int ditches = 0;
  int passages = 0;                       ///< walls with one gap across the world
  double narrowest_passage_m = 0.0;       ///< the smallest gap (0: no passage) [m]
  double roughness_rms_m = 0.0;
};

struct GeneratedWorld {
  WorldSpec world;
  WorldFeatures features;
  int attempts = 1;  ///< candidates drawn until one passed the check
};

/// The clearance beyond half the robot's width with which a world of difficulty d is to be
/// checked solvable (the caller's SolvableCheck) [m]: 0.1 m; 0.2 m for hard worlds, whose
/// clutter with 0.1 m left passages of 0.8 m on the way, in which MRPT's navigator circles
/// until the time limit even on the true map (docs/NAVIGATION.md, "Navigation benchmark").
/// With 0.2 m every passage on a hard world's way is about as wide as its narrowest wall gap.
double solvableClearance(Difficulty d);

/// A candidate world passes when the robot can drive from its start to its goal.
using SolvableCheck = std::function<bool(const WorldSpec&)>;

/// The world of params.seed (header comment). Throws std::invalid_argument for bad params and
/// std::runtime_error when no candidate passes the check within max_attempts.
GeneratedWorld generateWorld(const WorldGenParams& params, const SolvableCheck& solvable);

}  // namespace upd::sim
