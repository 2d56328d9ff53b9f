// `upd navigate`: the closed loop in simulation (scenario.h). A kinematic Dune, a generated
// world, a depth camera rendered at every step, the UPD (or the roughness index), the fused map
// and MRPT's reactive navigator, until the goal, a navigator error or the time limit.
#include "cli.h"
#include "commands.h"
#include "nav_run_config.h"
#include "output_folder.h"

#include "upd/nav/nav_config.h"
#include "upd/nav/scenario.h"
#include "upd/sim/terrain.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace upd::app {

const char* const kNavigateUsage =
    "usage: upd navigate --scenario NAME --output DIR [--config FILE.ini]\n"
    "                    [--nav-config FILE.ini] [--obstacles upd|roughness] [--max-time-s S]\n"
    "                    [--quiet]\n"
    "  Drives a simulated Dune from the world's start to its goal with MRPT's reactive\n"
    "  navigator avoiding what the UPD marks non-traversable, and writes into DIR:\n"
    "    navigation.reactivenavlog  MRPT navlog (open it with navlog-viewer)\n"
    "    trajectory.csv             pose, command, clearance and collision per step\n"
    "    path_map.png               the path over the fused traversability map\n"
    "    path_truth.png             the path over the ground truth\n"
    "    summary.json               reached, navigator end state and error, simulated time,\n"
    "                               path length, minimum clearance, collisions\n"
    "  Exit status: 0 goal reached, 3 run ended without reaching it (navigator error or time\n"
    "  limit; the outputs are written), 1 error, 2 bad usage.\n\n"
    "options:\n"
    "  --scenario NAME     rocks, ramp, ditch, corridor, trapped or mixed (required)\n"
    "  --output DIR        output directory, created if missing (required)\n"
    "  --config FILE       robot config: UPD pipeline, map, fusion, baseline\n"
    "                      (default config/dune-kinect.ini)\n"
    "  --nav-config FILE   navigation config: body, camera, obstacles, navigator, loop\n"
    "                      (default config/dune-nav.ini; its ptg_ini names the MRPT PTG file)\n"
    "  --obstacles M       upd (default) or roughness: the roughness-index baseline\n"
    "  --max-time-s S      simulated time limit [s] (default: [LoopParams] max_time_s)\n"
    "  --quiet             no progress lines\n";

int runNavigate(const std::vector<std::string>& argv) {
  const Args args(
      argv, {"--scenario", "--output", "--config", "--nav-config", "--obstacles", "--max-time-s"},
      {"--quiet"});
  if (!args.positionals().empty()) throw UsageError("unexpected argument " + args.positionals()[0]);
  const auto scenario = args.str("--scenario");
  if (!scenario) throw UsageError("--scenario NAME is required");
  const auto out = args.str("--output");
  if (!out) throw UsageError("--output DIR is required");
  nav::ObstacleDetector detector = nav::ObstacleDetector::Upd;
  if (const auto m = args.str("--obstacles")) {
    try {
      detector = nav::parseObstacleDetector(*m);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("option --obstacles: ") + e.what());
    }
  }
  const sim::WorldSpec world = sim::makeWorld(*scenario);  // throws listing the valid names

  nav::NavConfig config = loadNavConfigs(navConfigPaths(args));
  if (const auto t = args.number("--max-time-s")) {
    if (!(*t > 0))
      throw UsageError("option --max-time-s = " + std::to_string(*t) + ": must be > 0");
    config.loop.max_time_s = *t;
  }
  const bool quiet = args.flag("--quiet");

  const std::string navlog = (std::filesystem::path(*out) / "navigation.reactivenavlog").string();
  OutputFolder out_folder(*out);  // removed again, if empty, when the run fails
  if (!quiet) {
    std::printf("%s (%s): start (%.2f, %.2f), goal (%.2f, %.2f)\n", scenario->c_str(),
                nav::toString(detector), world.start_xy_yaw.x(), world.start_xy_yaw.y(),
                world.goal_xy.x(), world.goal_xy.y());
    std::fflush(stdout);
  }
  double next_report_s = 10.0;
  const auto progress = [&](const nav::TrajectorySample& s) {
    if (quiet || s.t_s < next_report_s) return;
    next_report_s += 10.0;
    const double d = std::hypot(s.pose_world_robot.x_m - world.goal_xy.x(),
                                s.pose_world_robot.y_m - world.goal_xy.y());
    std::printf("  t = %5.1f s  pose (%5.2f, %5.2f)  %.2f m to the goal\n", s.t_s,
                s.pose_world_robot.x_m, s.pose_world_robot.y_m, d);
    std::fflush(stdout);
  };
  const nav::ScenarioResult r =
      nav::runScenario(world, *scenario, config, detector, navlog, progress);
  nav::writeScenarioOutputs(r, world, config.body, *out);
  out_folder.keep();

  std::printf(
      "%s (%s): %s after %.1f s (%d steps), %.2f m driven, %d collisions, "
      "min clearance %.2f m, %.2f m from the goal\n",
      scenario->c_str(), nav::toString(detector), nav::toString(r.end), r.sim_time_s, r.steps,
      r.path_length_m, r.collision_steps, r.min_clearance_m, r.final_distance_to_goal_m);
  if (!r.navigator.error_code.empty()) {
    std::printf("  navigator: %s %s: %s\n", nav::toString(r.navigator.state),
                r.navigator.error_code.c_str(), r.navigator.error_message.c_str());
  }
  std::printf("  outputs in %s (navlog: navigation.reactivenavlog)\n", out->c_str());
  return r.reached ? 0 : 3;
}

}  // namespace upd::app
