// `upd simulate`: records a simulated Dune run through a generated world as an MRPT rawlog,
// with its ground-truth poses and traversability grid beside it (simulated_run.h).
#include "cli.h"
#include "commands.h"
#include "run_config.h"

#include "upd/core/stopwatch.h"
#include "upd/mrpt_bridge/simulated_run.h"
#include "upd/sim/terrain.h"

#include <cstdio>
#include <filesystem>

namespace upd::app {

const char* const kSimulateUsage =
    "usage: upd simulate --world NAME --output FILE.rawlog [--config FILE.ini] [--frames N]\n"
    "                    [--distance-m D]\n"
    "  Drives a virtual Dune ([RobotBodyParams], a Kinect on it as [CameraMountParams])\n"
    "  from the world's start to its goal and back (round its course: loop), and records a\n"
    "  real MRPT rawlog: 640 x 480\n"
    "  CObservation3DRangeScan frames with Kinect noise and odometry with drift. Beside it:\n"
    "  FILE.gt.tum (ground-truth poses, TUM format) and FILE.truth.pgm/.yaml (the world's\n"
    "  ground-truth traversability grid, ROS map_server format).\n\n"
    "options:\n"
    "  --world NAME      mixed, rocks, ramp, ditch, corridor, trapped, loop (default mixed)\n"
    "  --output FILE     the rawlog to write (required; its folder is made when missing)\n"
    "  --config FILE     [SimulationParams] (speed, frame spacing, drift, seed),\n"
    "                    [RobotBodyParams] and [CameraMountParams] (the robot and its camera)\n"
    "  --frames N        stop after N frames (default: the whole route)\n"
    "  --distance-m D    drive D metres, repeating the route (laps of loop's 140 m course);\n"
    "                    overrides [SimulationParams] distance_m\n";

int runSimulate(const std::vector<std::string>& argv) {
  const Args args(argv, {"--world", "--output", "--config", "--frames", "--distance-m"}, {});
  if (!args.positionals().empty()) throw UsageError("unexpected argument " + args.positionals()[0]);
  const auto out = args.str("--output");
  if (!out) throw UsageError("--output FILE.rawlog is required");
  RunConfig config = args.has("--config") ? loadRunConfig(*args.str("--config")) : RunConfig{};
  if (const auto d = args.number("--distance-m")) {
    if (!(*d > 0)) throw UsageError("option --distance-m = " + std::to_string(*d) + ": must be > 0");
    config.simulation.distance_m = *d;
  }
  const int frames = args.integer("--frames").value_or(0);
  if (frames < 0) throw UsageError("option --frames = " + std::to_string(frames) + ": must be >= 0");
  const sim::WorldSpec world = sim::makeWorld(args.str("--world").value_or("mixed"));
  // As `upd playback --output DIR` makes its folder, the rawlog's folder is made when missing.
  const std::filesystem::path folder = std::filesystem::path(*out).parent_path();
  if (!folder.empty()) std::filesystem::create_directories(folder);
  const core::Stopwatch watch;
  const auto s = mrpt_bridge::simulateRun(world, config.simulation, *out, frames);
  const double secs = watch.elapsedMs() / 1000.0;
  std::printf("%s: %zu frames over %.1f m (%.0f s of driving) in %.1f s\n  poses: %s\n  truth: %s\n",
              s.rawlog_path.c_str(), s.frames, s.path_length_m, s.duration_s, secs,
              s.poses_path.c_str(), s.truth_yaml_path.c_str());
  return 0;
}

}  // namespace upd::app
