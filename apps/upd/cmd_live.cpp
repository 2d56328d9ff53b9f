// `upd live`: a Kinect or Xtion (or an .oni recording) through OpenNI2, the UPD and the fused
// map at sensor rate, an optional 3D view, and navigation to a goal through a RobotBase. The
// base shipped is the simulated differential drive (robot_base.h): integrators replace it with
// their robot's (docs/NAVIGATION.md, "Driving a real robot").
#include "cli.h"
#include "commands.h"
#include "run_config.h"

#include "upd/io/json_io.h"
#include "upd/maps/grid_export.h"
#include "upd/nav/depth_camera.h"
#include "upd/nav/live_view.h"
#include "upd/nav/nav_config.h"
#include "upd/nav/navigation_loop.h"
#include "upd/sim/robot.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
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

std::atomic<bool> g_stop{false};
void onSignal(int) { g_stop = true; }

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

}  // namespace

int runLive(const std::vector<std::string>& argv) {
  const Args args(argv, {"--config", "--nav-config", "--oni", "--navigate", "--frames", "--output"},
                  {"--view"});
  if (!args.positionals().empty()) throw UsageError("unexpected argument " + args.positionals()[0]);
  const auto config_path =
      args.str("--config").value_or(nav::defaultConfigDir() + "/dune-kinect.ini");
  const auto nav_path =
      args.str("--nav-config").value_or(nav::defaultConfigDir() + "/dune-nav.ini");
  loadRunConfig(config_path);  // the shared robot config, checked strictly as every command does
  const nav::NavConfig config = nav::loadNavConfig(config_path, nav_path);
  const int max_frames = args.integer("--frames").value_or(0);
  if (max_frames < 0)
    throw UsageError("option --frames = " + std::to_string(max_frames) + ": must be >= 0");
  std::optional<Eigen::Vector2d> goal;
  if (const auto g = args.str("--navigate")) goal = parseGoal(*g);
  const auto out = args.str("--output");
  if (args.flag("--view") && !nav::displayAvailable()) {
    throw std::runtime_error("--view needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set)");
  }

  nav::OpenNI2Camera camera(args.str("--oni").value_or(""));  // one line and status 1 if none
  std::printf("camera: %s\n", camera.description().c_str());

  nav::SimulatedDiffDrive base({}, config.base);
  const std::string navlog =
      out && goal ? (std::filesystem::path(*out) / "navigation.reactivenavlog").string() : "";
  nav::NavigationLoop loop(base, config, nav::ObstacleDetector::Upd, navlog);
  std::unique_ptr<nav::LiveView> view;
  if (args.flag("--view")) view = std::make_unique<nav::LiveView>("upd live", config.body);
  if (goal) loop.navigateTo(*goal);

  g_stop = false;
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  const Eigen::Isometry3d camera_on_robot = sim::cameraOnRobot(config.camera);
  const auto t0 = std::chrono::steady_clock::now();
  auto last = t0, last_report = t0;
  int frames = 0;
  double score_ms = 0;
  nav::NavState state = nav::NavState::Navigating;
  std::string end = "stopped";
  nav::DepthFrame raw;
  while (!g_stop) {
    if (max_frames > 0 && frames >= max_frames) {
      end = "frame limit";
      break;
    }
    if (!camera.read(raw)) {
      end = "end of the recording";
      break;
    }
    const nav::DepthFrame frame = nav::decimate(raw, config.camera.image_downscale);
    const auto now = std::chrono::steady_clock::now();
    const double dt = std::chrono::duration<double>(now - last).count();
    last = now;
    if (dt > 0) base.advance(dt);
    nav::BaseState s;
    base.readState(s);
    const Eigen::Vector3d xy_yaw(s.pose_world_robot.x_m, s.pose_world_robot.y_m,
                                 s.pose_world_robot.yaw_rad);
    const PointCloud cloud_world = transformCloud(depthToCloud(frame.depth, frame.K),
                                                  sim::bodyPoseFlat(xy_yaw) * camera_on_robot);
    const nav::FrameEvidence& ev = loop.addFrame(cloud_world, base.timeS());
    score_ms += ev.score_ms;
    ++frames;
    if (goal) {
      state = loop.step();
      if (state != nav::NavState::Navigating) {
        end = state == nav::NavState::Idle && loop.outcome().target_reached ? "goal reached"
                                                                            : "navigator stopped";
        break;
      }
    }
    if (view) {
      if (!view->isOpen()) {
        end = "window closed";
        break;
      }
      view->update(ev, loop.grid(), s.pose_world_robot, goal ? &loop.route() : nullptr);
    }
    if (std::chrono::duration<double>(now - last_report).count() >= 1.0) {
      last_report = now;
      const double secs = std::chrono::duration<double>(now - t0).count();
      std::printf("frame %d  %.1f Hz  UPD %.0f ms/frame  %zu non-traversable  pose (%.2f, %.2f)\n",
                  frames, frames / secs, score_ms / frames, ev.obstacles_world.size(),
                  s.pose_world_robot.x_m, s.pose_world_robot.y_m);
      std::fflush(stdout);
    }
  }
  if (g_stop) end = "interrupted";
  const nav::NavOutcome outcome = loop.outcome();
  loop.finish();
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);

  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto stats = maps::computeStats(loop.grid());
  std::printf("%s: %d frames in %.1f s (%.1f Hz), map %zu known cells (%zu non-traversable)\n",
              end.c_str(), frames, secs, secs > 0 ? frames / secs : 0.0, stats.known,
              stats.non_traversable);
  if (!outcome.error_code.empty()) {
    std::printf("  navigator: %s %s: %s\n", nav::toString(outcome.state),
                outcome.error_code.c_str(), outcome.error_message.c_str());
  }
  if (out) {
    std::filesystem::create_directories(*out);
    maps::writeColourPng(loop.grid(), (std::filesystem::path(*out) / "map.png").string());
    nlohmann::json j;
    j["end"] = end;
    j["frames"] = frames;
    j["seconds"] = secs;
    j["mean_frame_scoring_ms"] = frames > 0 ? score_ms / frames : 0.0;
    j["map_known_cells"] = stats.known;
    j["map_non_traversable_cells"] = stats.non_traversable;
    if (goal) {
      j["goal_xy_m"] = {goal->x(), goal->y()};
      j["navigator"] = {{"state", nav::toString(outcome.state)},
                        {"target_reached_event", outcome.target_reached},
                        {"error_code", outcome.error_code},
                        {"error_message", outcome.error_message}};
    }
    io::writeJsonAtomically((std::filesystem::path(*out) / "summary.json").string(), j);
    std::printf("  outputs in %s\n", out->c_str());
  }
  if (goal) return outcome.target_reached ? 0 : 3;
  return 0;
}

}  // namespace upd::app
