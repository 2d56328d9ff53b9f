// `upd live`: a Kinect or Xtion (or an .oni recording) through OpenNI2, the UPD and the fused
// map at sensor rate, an optional 3D view, and navigation to a goal through a RobotBase. The
// base shipped is the simulated differential drive (robot_base.h): integrators replace it with
// their robot's (docs/NAVIGATION.md, "Driving a real robot"). The camera input is built when
// OpenNI2 was found (libs/openni2, UPD_HAVE_OPENNI2); without it `upd live` says so.
#include "cli.h"
#include "commands.h"
#include "run_config.h"
#include "stop_signal.h"

#include "upd/io/json_io.h"
#include "upd/maps/grid_export.h"
#include "upd/nav/live_view.h"
#include "upd/nav/nav_config.h"
#include "upd/nav/navigation_loop.h"
#include "upd/sim/robot.h"

#ifdef UPD_HAVE_OPENNI2
#include "upd/openni2/depth_camera.h"
#endif

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>

namespace upd::app {

const char* const kLiveUsage =
    "usage: upd live [--config FILE.ini] [--nav-config FILE.ini] [--oni FILE.oni] [--view]\n"
    "                [--navigate X,Y] [--frames N] [--output DIR]\n"
    "  Reads a Kinect or Xtion through OpenNI2 (or an .oni recording), runs the UPD and the\n"
    "  traversability map on every frame and, with --navigate, drives the robot base to the\n"
    "  goal with MRPT's reactive navigator. The shipped base is simulated (it moves on the\n"
    "  velocity commands, the camera does not): see docs/NAVIGATION.md to plug in a real one.\n"
    "  Without a device (and no --oni) it says so and exits with status 1. Ctrl-C stops.\n\n"
    "options:\n"
    "  --config FILE      robot config (default config/dune-kinect.ini)\n"
    "  --nav-config FILE  navigation config: camera mount, obstacles, navigator\n"
    "                     (default config/dune-nav.ini)\n"
    "  --oni FILE         play an OpenNI2 recording instead of a live device\n"
    "  --view             3D view: cloud coloured by zeta, the map, the robot, the route\n"
    "  --navigate X,Y     goal in the map frame (the robot starts at 0,0 facing +x) [m]\n"
    "  --frames N         stop after N frames (default: until the end, the goal or Ctrl-C)\n"
    "  --output DIR       write map.png, summary.json and the navlog (with --navigate) at the "
    "end\n";

namespace {

using Clock = std::chrono::steady_clock;

Eigen::Vector2d parseGoal(const std::string& text) {
  std::istringstream is(text);
  double x = 0, y = 0;
  char comma = 0;
  if (!(is >> x >> comma >> y) || comma != ',' || !(is >> std::ws).eof() || !std::isfinite(x) ||
      !std::isfinite(y)) {
    throw UsageError("option --navigate = '" + text + "': expected X,Y in metres");
  }
  return {x, y};
}

struct LiveOptions {
  std::string config_path, nav_path;
  std::string oni;     ///< empty: the first connected device
  int max_frames = 0;  ///< 0: no limit
  std::optional<Eigen::Vector2d> goal;
  std::optional<std::string> out;
  bool view = false;
};

// The command line; the default configs are looked up only when not given.
LiveOptions parseLiveOptions(const std::vector<std::string>& argv) {
  const Args args(argv, {"--config", "--nav-config", "--oni", "--navigate", "--frames", "--output"},
                  {"--view"});
  if (!args.positionals().empty()) throw UsageError("unexpected argument " + args.positionals()[0]);
  LiveOptions o;
  const auto config = args.str("--config");
  o.config_path = config ? *config : nav::defaultConfigDir() + "/dune-kinect.ini";
  const auto nav_config = args.str("--nav-config");
  o.nav_path = nav_config ? *nav_config : nav::defaultConfigDir() + "/dune-nav.ini";
  o.oni = args.str("--oni").value_or("");
  o.max_frames = args.integer("--frames").value_or(0);
  if (o.max_frames < 0)
    throw UsageError("option --frames = " + std::to_string(o.max_frames) + ": must be >= 0");
  if (const auto g = args.str("--navigate")) o.goal = parseGoal(*g);
  o.out = args.str("--output");
  o.view = args.flag("--view");
  return o;
}

#ifdef UPD_HAVE_OPENNI2

/// What one run did, for the summary line and summary.json.
struct LiveTally {
  std::string end;
  int frames = 0;
  double seconds = 0;
  double score_ms = 0;  ///< summed over the frames
  nav::NavOutcome outcome;
};

void printSummary(const LiveTally& t, const maps::GridStats& stats) {
  std::printf("%s: %d frames in %.1f s (%.1f Hz), map %zu known cells (%zu non-traversable)\n",
              t.end.c_str(), t.frames, t.seconds, t.seconds > 0 ? t.frames / t.seconds : 0.0,
              stats.known, stats.non_traversable);
  if (!t.outcome.error_code.empty()) {
    std::printf("  navigator: %s %s: %s\n", nav::toString(t.outcome.state),
                t.outcome.error_code.c_str(), t.outcome.error_message.c_str());
  }
}

// map.png and summary.json in dir.
void writeLiveOutputs(const std::string& dir, const LiveOptions& o, const LiveTally& t,
                      const maps::TraversabilityGrid& grid, const maps::GridStats& stats) {
  std::filesystem::create_directories(dir);
  maps::writeColourPng(grid, (std::filesystem::path(dir) / "map.png").string());
  nlohmann::json j;
  j["end"] = t.end;
  j["frames"] = t.frames;
  j["seconds"] = t.seconds;
  j["mean_frame_scoring_ms"] = t.frames > 0 ? t.score_ms / t.frames : 0.0;
  j["map_known_cells"] = stats.known;
  j["map_non_traversable_cells"] = stats.non_traversable;
  if (o.goal) {
    j["goal_xy_m"] = {o.goal->x(), o.goal->y()};
    j["navigator"] = {{"state", nav::toString(t.outcome.state)},
                      {"target_reached_event", t.outcome.target_reached},
                      {"error_code", t.outcome.error_code},
                      {"error_message", t.outcome.error_message}};
  }
  io::writeJsonAtomically((std::filesystem::path(dir) / "summary.json").string(), j);
  std::printf("  outputs in %s\n", dir.c_str());
}

// The robot, the navigation loop and the view of one run, and its counters.
struct LiveRun {
  LiveRun(const LiveOptions& o, const nav::NavConfig& c)
      : opt(o),
        config(c),
        base({}, c.base),
        loop(base, c, nav::ObstacleDetector::Upd,
             o.out && o.goal
                 ? (std::filesystem::path(*o.out) / "navigation.reactivenavlog").string()
                 : ""),
        camera_on_robot(sim::cameraOnRobot(c.camera)) {
    if (o.view) view = std::make_unique<nav::LiveView>("upd live", c.body);
    if (o.goal) loop.navigateTo(*o.goal);
    t0 = last = last_report = now = Clock::now();  // the run starts after the set-up
  }

  const LiveOptions& opt;
  const nav::NavConfig& config;
  nav::SimulatedDiffDrive base;
  nav::NavigationLoop loop;
  std::unique_ptr<nav::LiveView> view;
  const Eigen::Isometry3d camera_on_robot;
  Clock::time_point t0, last, last_report, now;
  int frames = 0;
  double score_ms = 0;
};

// Scores one camera frame into the map at the base's pose, advanced to the frame's arrival.
const nav::FrameEvidence& addFrame(LiveRun& run, const openni2::DepthFrame& raw,
                                   nav::BaseState& s) {
  const openni2::DepthFrame frame = openni2::decimate(raw, run.config.camera.image_downscale);
  run.now = Clock::now();
  const double dt = std::chrono::duration<double>(run.now - run.last).count();
  run.last = run.now;
  if (dt > 0) run.base.advance(dt);
  run.base.readState(s);
  const Eigen::Vector3d xy_yaw(s.pose_world_robot.x_m, s.pose_world_robot.y_m,
                               s.pose_world_robot.yaw_rad);
  const core::PointCloud cloud_world = core::transformCloud(core::depthToCloud(frame.depth, frame.K),
                                                sim::bodyPoseFlat(xy_yaw) * run.camera_on_robot);
  const nav::FrameEvidence& ev = run.loop.addFrame(cloud_world, run.base.timeS());
  run.score_ms += ev.timings.total_ms;
  ++run.frames;
  return ev;
}

// The navigator's step and the view after a frame: why the run ends, or nothing.
std::optional<std::string> afterFrame(LiveRun& run, const nav::FrameEvidence& ev,
                                      const nav::BaseState& s) {
  if (run.opt.goal) {
    const nav::NavState state = run.loop.step();
    if (state != nav::NavState::Navigating) {
      return state == nav::NavState::Idle && run.loop.outcome().target_reached
                 ? "goal reached"
                 : "navigator stopped";
    }
  }
  if (run.view) {
    if (!run.view->isOpen()) return "window closed";
    run.view->update(ev, run.loop.grid(), s.pose_world_robot,
                     run.opt.goal ? &run.loop.route() : nullptr);
  }
  return std::nullopt;
}

// One line a second: rate, scoring time, obstacles, pose.
void reportProgress(LiveRun& run, const nav::FrameEvidence& ev, const nav::BaseState& s) {
  if (std::chrono::duration<double>(run.now - run.last_report).count() < 1.0) return;
  run.last_report = run.now;
  const double secs = std::chrono::duration<double>(run.now - run.t0).count();
  std::printf("frame %d  %.1f Hz  UPD %.0f ms/frame  %zu non-traversable  pose (%.2f, %.2f)\n",
              run.frames, run.frames / secs, run.score_ms / run.frames, ev.obstacles_world.size(),
              s.pose_world_robot.x_m, s.pose_world_robot.y_m);
  std::fflush(stdout);
}

// Frames until the limit, the end of the recording, the goal, the window closing or a signal.
std::string runFrames(LiveRun& run, openni2::OpenNI2Camera& camera) {
  openni2::DepthFrame raw;
  while (!stopRequested()) {
    if (run.opt.max_frames > 0 && run.frames >= run.opt.max_frames) return "frame limit";
    if (!camera.read(raw)) return "end of the recording";
    nav::BaseState s;
    const nav::FrameEvidence& ev = addFrame(run, raw, s);
    if (const auto end = afterFrame(run, ev, s)) return *end;
    reportProgress(run, ev, s);
  }
  return "interrupted";
}

// The summary line, the outputs and the exit status of a run.
int finishLive(const LiveOptions& o, const LiveTally& t, const maps::TraversabilityGrid& grid) {
  const auto stats = maps::computeStats(grid);
  printSummary(t, stats);
  if (o.out) writeLiveOutputs(*o.out, o, t, grid, stats);
  if (o.goal) return t.outcome.target_reached ? 0 : 3;
  return 0;
}

// Runs the camera through the loop until it stops.
int runCamera(const LiveOptions& o, const nav::NavConfig& config) {
  openni2::OpenNI2Camera camera(o.oni);  // one line and status 1 if none
  std::printf("camera: %s\n", camera.description().c_str());
  LiveRun run(o, config);
  LiveTally t;
  {
    const StopOnSignal stop_on_signal;
    t.end = runFrames(run, camera);
    if (stopRequested()) t.end = "interrupted";
    t.outcome = run.loop.outcome();
    run.loop.finish();
  }
  t.seconds = std::chrono::duration<double>(Clock::now() - run.t0).count();
  t.frames = run.frames;
  t.score_ms = run.score_ms;
  return finishLive(o, t, run.loop.grid());
}

#else

int runCamera(const LiveOptions& o, const nav::NavConfig&) {
  const std::string why = "upd was built without OpenNI2 (install libopenni2-dev and rebuild)";
  throw std::runtime_error(o.oni.empty() ? "no OpenNI2 depth camera input: " + why
                                         : "cannot play " + o.oni + ": " + why);
}

#endif

}  // namespace

int runLive(const std::vector<std::string>& argv) {
  const LiveOptions o = parseLiveOptions(argv);
  loadRunConfig(o.config_path);  // the shared robot config, checked strictly as every command does
  const nav::NavConfig config = nav::loadNavConfig(o.config_path, o.nav_path);
  if (o.view && !nav::displayAvailable()) {
    throw std::runtime_error("--view needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set)");
  }
  return runCamera(o, config);
}

}  // namespace upd::app
