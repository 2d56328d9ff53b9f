// The closed loop in simulation (`upd navigate`): a kinematic Dune in a generated world
// (sim::makeWorld), its depth camera rendered from the body pose at every control step (upd/sim/
// robot.h), the UPD (or the roughness index), the fused map, MRPT's reactive navigator and its
// velocity commands, until the goal is reached, the navigator reports an error, or the time
// limit.
//
// Each step is checked against the ground truth (sim::TruthRaster): a collision is a step where
// the robot's footprint overlaps NonTraversable truth; clearance is the footprint's distance to
// it.
#pragma once

#include "upd/maps/traversability_grid.h"
#include "upd/nav/nav_config.h"
#include "upd/nav/navigation_loop.h"
#include "upd/nav/navigator.h"
#include "upd/nav/perception.h"
#include "upd/nav/robot_base.h"
#include "upd/nav/route_planner.h"
#include "upd/sim/robot.h"
#include "upd/sim/terrain.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace upd::nav {

/// The state after one control step.
struct TrajectorySample {
  double t_s = 0.0;  ///< simulated time [s]
  Pose2D pose_world_robot;
  double z_m = 0.0;                 ///< body height on the terrain [m]
  Twist2D command;                  ///< velocity command in force after the step
  double clearance_m = 0.0;         ///< footprint to NonTraversable truth [m], capped at the search
  bool collision = false;           ///< footprint overlaps NonTraversable truth
  std::size_t obstacle_points = 0;  ///< handed to the navigator
  std::size_t frame_nontraversable = 0;  ///< NonTraversable points in the step's frame
  NavState state = NavState::Navigating;
};

/// Why a run ended.
enum class RunEnd { GoalReached, NavigatorError, NavigatorStopped, TimeLimit };
const char* toString(RunEnd e);

struct ScenarioResult {
  std::string scenario;
  core::ObstacleDetector detector = core::ObstacleDetector::Upd;
  std::string perception;  ///< when not empty, named instead of the detector (e.g. "truth")
  Eigen::Vector2d goal_xy = Eigen::Vector2d::Zero();
  bool reached = false;  ///< the navigator reported the goal and the robot is within tolerance
  RunEnd end = RunEnd::TimeLimit;
  NavOutcome navigator;  ///< the navigator's end state and error
  double sim_time_s = 0.0;
  double path_length_m = 0.0;
  double min_clearance_m = 0.0;  ///< over the whole run [m]
  int collision_steps = 0;       ///< steps with the footprint on NonTraversable truth
  int steps = 0;
  double final_distance_to_goal_m = 0.0;
  double wall_time_s = 0.0;
  double mean_frame_ms = 0.0;                ///< scoring time per frame
  std::vector<TrajectorySample> trajectory;  ///< the start, then one sample per step
  maps::TraversabilityGrid grid;             ///< the fused map at the end
  Route route;                               ///< the last route the planner found
  int failed_plans = 0;                      ///< plans that found no route
  bool replanning_stopped = false;           ///< the loop stopped replanning for lack of progress
  int recoveries = 0;                        ///< recovery manoeuvres of the stalled robot
  std::string navlog_path;                   ///< empty when no navlog was written
};

/// Called after every step (progress display); may be empty.
using StepCallback = std::function<void(const TrajectorySample&)>;

/// Runs the loop on world (name is recorded). navlog_path: where the MRPT navlog goes (empty:
/// none). labeller: when set, labels the frames instead of the detector
/// (NavigationLoop::setLabeller). Restores MRPT's clock to real time when it returns.
ScenarioResult runScenario(const sim::WorldSpec& world, const std::string& name,
                           const NavConfig& config, core::ObstacleDetector detector,
                           const std::string& navlog_path = "", const StepCallback& on_step = {},
                           const NavigationLoop::PointLabeller& labeller = {});

/// summary.json's content: reached, end state, navigator error, simulated time, path length,
/// minimum clearance, collisions, ...
nlohmann::json summaryJson(const ScenarioResult& result);

/// Writes trajectory.csv, path_map.png (the path over the fused map), path_truth.png (over the
/// ground truth) and summary.json into output_dir (created if missing), each atomically.
/// The footprint (body) is drawn at the start and the end of the path.
void writeScenarioOutputs(const ScenarioResult& result, const sim::WorldSpec& world,
                          const sim::RobotBodyParams& body, const std::string& output_dir);

}  // namespace upd::nav
