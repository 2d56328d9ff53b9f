// The navigation benchmark (`upd bench-nav`): the closed loop of `upd navigate` (scenario.h) on
// generated worlds (upd/sim/world_generator.h), scored against the optimal path on the ground
// truth, with every failure put in one category.
//
// A world is solvable when the ground-truth planner of the simulated run
// (mrpt_bridge::planSimulatedRoute: the project's grid A* on the truth raster) finds a way from
// start to goal keeping half the robot's width plus the difficulty's clearance
// (sim::solvableClearance, unless footprint_margin_m says otherwise) from non-traversable truth. The optimal path is the same planner's
// straightened path keeping half the width (the bare footprint: no navigator can do shorter
// without touching an obstacle), the optimal time its length at reference_speed_mps (the
// navigator's top speed).
//
// Perception: the UPD, the roughness index, or the truth (the oracle: the camera's points
// labelled with the ground truth's traversability grown by oracle_margin_m, so only what the
// camera sees is known; the UPD's share of a failure is the difference to it).
//
// Outcome of a world: collision when any step's footprint overlaps non-traversable truth (even
// if the goal was reached after); otherwise success when the goal was reached, timeout at the
// time limit, stuck when the navigator gave up. Failure categories:
//  - missed_obstacle (perception): a collision where the fused map did not read the truth's
//    obstacle under the footprint as non-traversable;
//  - navigator: a collision with an obstacle the map knew, or a stop while the map still
//    holds a route to the goal and the planner kept planning;
//  - false_obstacle (perception): a stop where the final map holds no route from the robot to
//    the goal (the truth does: what closed the way is mapped obstacle that is not there);
//  - planning: a stop while the map holds a route but the loop's planner had given up at the
//    end (replanning stopped for lack of progress; plans that failed on the way do not count).
#pragma once

#include "upd/nav/nav_config.h"
#include "upd/nav/scenario.h"
#include "upd/sim/world_generator.h"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace upd::nav {

enum class BenchPerception { Upd, Roughness, Truth };
const char* toString(BenchPerception p);
/// "upd", "roughness" or "truth"; std::invalid_argument naming the valid values otherwise.
BenchPerception parseBenchPerception(const std::string& name);

enum class BenchOutcome { Success, Collision, Timeout, Stuck };
const char* toString(BenchOutcome o);
BenchOutcome parseBenchOutcome(const std::string& name);

enum class FailureCause { None, FalseObstacle, MissedObstacle, Planning, Navigator };
const char* toString(FailureCause c);

struct BenchParams {
  /// The solvability check's clearance beyond half the robot's width [m]; unset: the world's
  /// difficulty's (sim::solvableClearance: 0.1 m, hard worlds 0.2 m).
  std::optional<double> footprint_margin_m;
  double reference_speed_mps = 0.4;  ///< the optimal time is the optimal path at this [m/s]
  double time_limit_factor = 4.0;    ///< a world's time limit: this x the optimal time ...
  double min_time_limit_s = 60.0;    ///< ... and at least this [s]
  /// The oracle labels points this close to non-traversable truth non-traversable too [m]. 0:
  /// the oracle's clearance is the navigator polygon's margin (config/ptg-dune.ini), as the
  /// other modes'; a margin on top of it makes MRPT's navigator stop in front of gaps and
  /// rocks (docs/NAVIGATION.md, "Navigation benchmark").
  double oracle_margin_m = 0.0;

  void validate() const;  ///< std::invalid_argument naming the field
};

struct BenchWorld {
  sim::GeneratedWorld generated;
  std::vector<Eigen::Vector2d> optimal_path;  ///< start to goal on the ground truth, bare footprint
  double optimal_path_m = 0.0;
};

/// The world of gen.seed, solvable for body (see the header comment).
BenchWorld makeBenchWorld(const sim::WorldGenParams& gen, const sim::RobotBodyParams& body,
                          const BenchParams& params);

/// One world's line of worlds.csv.
struct BenchRow {
  int seed = 0;
  std::string difficulty, obstacles;
  BenchOutcome outcome = BenchOutcome::Stuck;
  FailureCause cause = FailureCause::None;
  double time_s = 0.0, path_m = 0.0;
  double optimal_path_m = 0.0, optimal_time_s = 0.0;
  double time_ratio = 0.0, path_ratio = 0.0;  ///< time / optimal time, path / optimal path
  double min_clearance_m = 0.0;
  int collision_steps = 0;
  double final_distance_m = 0.0;  ///< to the goal at the end [m]
  std::string end;                ///< the loop's end (goal reached, navigator error, ...)
  double wall_s = 0.0;
};

/// Runs the closed loop on world with perception p (the time limit from params). result, when
/// not null, receives the run (trajectory, map, route) for pictures.
BenchRow runBenchWorld(const BenchWorld& world, const NavConfig& config, BenchPerception p,
                       const BenchParams& params, ScenarioResult* result = nullptr);

/// The category of a failed run (None for a success); see the header comment.
FailureCause categorize(const ScenarioResult& run, const sim::WorldSpec& world,
                        const NavConfig& config, BenchOutcome outcome);

/// summary.json: worlds, success_rate, collisions (worlds), timeouts, stuck, time_ratio and
/// path_ratio (means over the successes), mean_time_s (successes), min_clearance_m (over all
/// worlds), failures per category.
nlohmann::json benchSummary(const std::vector<BenchRow>& rows);

/// worlds.csv, atomically (header line, one row per world).
void writeBenchCsv(const std::string& path, const std::vector<BenchRow>& rows);
/// Reads a worlds.csv; throws std::runtime_error naming the file and line when malformed.
std::vector<BenchRow> readBenchCsv(const std::string& path);

/// The differences of actual from expected (matched by seed, difficulty and obstacles): a
/// world missing, another outcome, or a ratio of a success off by more than ratio_tolerance.
/// Empty when they agree.
std::vector<std::string> compareBench(const std::vector<BenchRow>& expected,
                                      const std::vector<BenchRow>& actual,
                                      double ratio_tolerance);

}  // namespace upd::nav
