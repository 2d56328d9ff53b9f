// The benchmark's worlds and runs: solvability and the optimal path on the ground truth, the
// closed loop per world, the outcome and the failure category (upd/nav/bench.h).
#include "upd/nav/bench.h"

#include "upd/mrpt_bridge/simulated_run.h"
#include "upd/maps/traversability_grid.h"
#include "upd/nav/obstacles.h"
#include "upd/nav/route_planner.h"
#include "upd/sim/truth_raster.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

namespace upd::nav {

const char* toString(BenchPerception p) {
  switch (p) {
    case BenchPerception::Upd: return "upd";
    case BenchPerception::Roughness: return "roughness";
    case BenchPerception::Truth: return "truth";
  }
  return "?";
}

BenchPerception parseBenchPerception(const std::string& name) {
  if (name == "upd") return BenchPerception::Upd;
  if (name == "roughness") return BenchPerception::Roughness;
  if (name == "truth") return BenchPerception::Truth;
  throw std::invalid_argument("obstacles '" + name + "': expected upd, roughness or truth");
}

const char* toString(BenchOutcome o) {
  switch (o) {
    case BenchOutcome::Success: return "success";
    case BenchOutcome::Collision: return "collision";
    case BenchOutcome::Timeout: return "timeout";
    case BenchOutcome::Stuck: return "stuck";
  }
  return "?";
}

BenchOutcome parseBenchOutcome(const std::string& name) {
  for (BenchOutcome o : {BenchOutcome::Success, BenchOutcome::Collision, BenchOutcome::Timeout,
                         BenchOutcome::Stuck}) {
    if (name == toString(o)) return o;
  }
  throw std::invalid_argument("outcome '" + name + "': expected success, collision, timeout or stuck");
}

const char* toString(FailureCause c) {
  switch (c) {
    case FailureCause::None: return "none";
    case FailureCause::FalseObstacle: return "false_obstacle";
    case FailureCause::MissedObstacle: return "missed_obstacle";
    case FailureCause::Planning: return "planning";
    case FailureCause::Navigator: return "navigator";
  }
  return "?";
}

void BenchParams::validate() const {
  const char* s = "BenchParams";
  if (footprint_margin_m) {
    core::requireParam(std::isfinite(*footprint_margin_m) && *footprint_margin_m >= 0, s,
                       "footprint_margin_m", *footprint_margin_m, "must be >= 0");
  }
  core::requireParam(std::isfinite(reference_speed_mps) && reference_speed_mps > 0, s,
                     "reference_speed_mps", reference_speed_mps, "must be > 0");
  core::requireParam(std::isfinite(time_limit_factor) && time_limit_factor >= 1, s,
                     "time_limit_factor", time_limit_factor, "must be >= 1");
  core::requireParam(std::isfinite(min_time_limit_s) && min_time_limit_s > 0, s,
                     "min_time_limit_s", min_time_limit_s, "must be > 0");
  core::requireParam(std::isfinite(oracle_margin_m) && oracle_margin_m >= 0, s,
                     "oracle_margin_m", oracle_margin_m, "must be >= 0");
}

namespace {

// The straightened path on the ground truth keeping the footprint's clearance; empty when
// there is none (mrpt_bridge::planSimulatedRoute throws std::invalid_argument then).
std::vector<Eigen::Vector2d> truthPath(const sim::WorldSpec& world,
                                       const sim::RobotBodyParams& body, double margin_m) {
  mrpt_bridge::SimulationParams p;
  p.body = body;
  p.clearance_m = 0.5 * body.width_m + margin_m;
  p.return_to_start = false;
  std::vector<Eigen::Vector2d> path;
  try {
    for (const auto& pose : mrpt_bridge::planSimulatedRoute(world, p)) {
      const Eigen::Vector2d xy = pose.pose_world_robot.translation().head<2>();
      if (path.empty() || (xy - path.back()).norm() > 1e-9) path.push_back(xy);
    }
  } catch (const std::invalid_argument&) {
    path.clear();
  }
  return path;
}

double polylineLength(const std::vector<Eigen::Vector2d>& path) {
  double len = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) len += (path[i] - path[i - 1]).norm();
  return len;
}

}  // namespace

BenchWorld makeBenchWorld(const sim::WorldGenParams& gen, const sim::RobotBodyParams& body,
                          const BenchParams& params) {
  params.validate();
  BenchWorld w;
  const double margin_m =
      params.footprint_margin_m.value_or(sim::solvableClearance(gen.difficulty));
  const auto solvable = [&](const sim::WorldSpec& candidate) {
    return !truthPath(candidate, body, margin_m).empty();
  };
  w.generated = sim::generateWorld(gen, solvable);
  // The optimum is the shortest way of the bare footprint: a navigator may pass closer than the
  // check's margin, and its path must not come out shorter than the optimum.
  w.optimal_path = truthPath(w.generated.world, body, 0.0);
  w.optimal_path_m = polylineLength(w.optimal_path);
  return w;
}

namespace {

BenchOutcome outcomeOf(const ScenarioResult& r) {
  if (r.collision_steps > 0) return BenchOutcome::Collision;
  if (r.reached) return BenchOutcome::Success;
  return r.end == RunEnd::TimeLimit ? BenchOutcome::Timeout : BenchOutcome::Stuck;
}

// At the first collision: did the map read the truth's obstacle under the footprint as one?
FailureCause collisionCause(const ScenarioResult& run, const sim::WorldSpec& world,
                            const NavConfig& config) {
  const sim::TruthRaster truth(world.terrain, config.loop.truth_cell_m);
  const auto hit = std::find_if(run.trajectory.begin(), run.trajectory.end(),
                                [](const TrajectorySample& s) { return s.collision; });
  if (hit == run.trajectory.end()) return FailureCause::None;
  const Pose2D& p = hit->pose_world_robot;
  const double reach = 0.5 * std::hypot(config.body.length_m, config.body.width_m);
  const double c = std::cos(p.yaw_rad), s = std::sin(p.yaw_rad);
  for (int iy = 0; iy < truth.sizeY(); ++iy) {
    for (int ix = 0; ix < truth.sizeX(); ++ix) {
      const Eigen::Vector2d q = truth.cellCenter(ix, iy);
      const double dx = q.x() - p.x_m, dy = q.y() - p.y_m;
      if (std::abs(dx) > reach || std::abs(dy) > reach) continue;
      if (truth.at(ix, iy) != core::Label::NonTraversable) continue;
      const double u = c * dx + s * dy, v = -s * dx + c * dy;
      if (std::abs(u) > 0.5 * config.body.length_m || std::abs(v) > 0.5 * config.body.width_m) {
        continue;
      }
      if (maps::cellLabel(run.grid, q.x(), q.y()) == core::Label::NonTraversable) {
        return FailureCause::Navigator;  // the map knew it: the navigator drove into it
      }
    }
  }
  return FailureCause::MissedObstacle;
}

}  // namespace

FailureCause categorize(const ScenarioResult& run, const sim::WorldSpec& world,
                        const NavConfig& config, BenchOutcome outcome) {
  if (outcome == BenchOutcome::Success) return FailureCause::None;
  if (outcome == BenchOutcome::Collision) return collisionCause(run, world, config);
  // Stopped short: does the final map still hold a way from where the robot stands?
  const Pose2D& end = run.trajectory.back().pose_world_robot;
  std::vector<Eigen::Vector2d> fence;
  if (config.loop.fence_world) {
    fence = rectangleFence(world.terrain.minXY(), world.terrain.maxXY(),
                           config.obstacles.decimation_m);
  }
  const Route r = planRoute(run.grid, fence, {end.x_m, end.y_m}, world.goal_xy, config.route);
  if (!r.found) return FailureCause::FalseObstacle;
  // The planner's state at the end: it had stopped replanning (the navigator was left on a
  // stale route); plans that failed earlier on the way do not count.
  if (run.replanning_stopped) return FailureCause::Planning;
  return FailureCause::Navigator;
}

namespace {

// The oracle's labeller: the ground truth rasterised, its NonTraversable cells grown by
// margin_m (the oracle keeps that clearance, as the UPD's band does), looked up per point.
NavigationLoop::PointLabeller truthLabeller(const sim::WorldSpec& world, double cell_m,
                                            double margin_m) {
  const sim::TruthRaster truth(world.terrain, cell_m);
  const int nx = truth.sizeX(), ny = truth.sizeY();
  auto labels = std::make_shared<std::vector<core::Label>>(static_cast<std::size_t>(nx) * ny);
  const int reach = static_cast<int>(std::floor(margin_m / cell_m));
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      (*labels)[static_cast<std::size_t>(iy) * nx + ix] = truth.at(ix, iy);
    }
  }
  for (int iy = 0; iy < ny; ++iy) {
    for (int ix = 0; ix < nx; ++ix) {
      if (truth.at(ix, iy) != core::Label::NonTraversable) continue;
      for (int dy = -reach; dy <= reach; ++dy) {
        for (int dx = -reach; dx <= reach; ++dx) {
          const int jx = ix + dx, jy = iy + dy;
          const bool inside = jx >= 0 && jy >= 0 && jx < nx && jy < ny;
          if (!inside || (dx * dx + dy * dy) * cell_m * cell_m > margin_m * margin_m) continue;
          (*labels)[static_cast<std::size_t>(jy) * nx + jx] = core::Label::NonTraversable;
        }
      }
    }
  }
  const Eigen::Vector2d origin = truth.origin();
  return [labels, origin, cell_m, nx, ny](double x, double y) {
    const auto ix = static_cast<int>(std::floor((x - origin.x()) / cell_m));
    const auto iy = static_cast<int>(std::floor((y - origin.y()) / cell_m));
    if (ix < 0 || iy < 0 || ix >= nx || iy >= ny) return core::Label::Unknown;
    return (*labels)[static_cast<std::size_t>(iy) * nx + ix];
  };
}

}  // namespace

BenchRow runBenchWorld(const BenchWorld& world, const NavConfig& config, BenchPerception p,
                       const BenchParams& params, ScenarioResult* result) {
  params.validate();
  const sim::WorldSpec& spec = world.generated.world;
  BenchRow row;
  row.seed = 0;
  row.obstacles = toString(p);
  row.optimal_path_m = world.optimal_path_m;
  row.optimal_time_s = world.optimal_path_m / params.reference_speed_mps;
  NavConfig c = config;
  c.loop.max_time_s = std::max(params.min_time_limit_s, params.time_limit_factor * row.optimal_time_s);
  const auto detector =
      p == BenchPerception::Roughness ? core::ObstacleDetector::Roughness : core::ObstacleDetector::Upd;
  const NavigationLoop::PointLabeller labeller =
      p == BenchPerception::Truth ? truthLabeller(spec, c.loop.truth_cell_m, params.oracle_margin_m)
                                  : NavigationLoop::PointLabeller{};
  ScenarioResult r = runScenario(spec, "bench", c, detector, "", {}, labeller);
  r.perception = toString(p);
  row.outcome = outcomeOf(r);
  row.cause = categorize(r, spec, c, row.outcome);
  row.time_s = r.sim_time_s;
  row.path_m = r.path_length_m;
  row.time_ratio = row.optimal_time_s > 0 ? row.time_s / row.optimal_time_s : 0.0;
  row.path_ratio = row.optimal_path_m > 0 ? row.path_m / row.optimal_path_m : 0.0;
  row.min_clearance_m = r.min_clearance_m;
  row.collision_steps = r.collision_steps;
  row.final_distance_m = r.final_distance_to_goal_m;
  row.end = toString(r.end);
  row.wall_s = r.wall_time_s;
  if (result != nullptr) *result = std::move(r);
  return row;
}

}  // namespace upd::nav
