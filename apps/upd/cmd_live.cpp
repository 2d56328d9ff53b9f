// `upd live`: frames from a live source (live_source.h: OpenNI2, libfreenect, or any MRPT
// sensor file), each scored as `upd playback` scores a rawlog's observation (observation ->
// cloud in the robot frame -> world frame at the base's pose) and fused into the map at sensor
// rate, an optional 3D view, navigation to a goal through a RobotBase, an optional recording
// (rawlog_writer.h) and a watchdog that stops the robot when the source stops
// (live_watchdog.h). The base shipped is the simulated differential drive (robot_base.h):
// integrators replace it with their robot's (docs/NAVIGATION.md, "Driving a real robot").
#include "calibrate_mount.h"
#include "cli.h"
#include "commands.h"
#include "live_base.h"
#include "live_options.h"
#include "live_source.h"
#include "live_view.h"
#include "live_watchdog.h"
#include "output_folder.h"
#include "run_config.h"
#include "stop_signal.h"

#include "upd/core/version.h"
#include "upd/io/json_io.h"
#include "upd/maps/grid_export.h"
#include "upd/mrpt_bridge/observation_cloud.h"
#include "upd/mrpt_bridge/rawlog_writer.h"
#include "upd/nav/nav_config.h"
#include "upd/nav/navigation_loop.h"
#include "upd/sim/robot.h"

#include <mrpt/obs/CObservation.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

namespace upd::app {

const char* const kLiveUsage =
    "usage: upd live [SOURCE] [--config FILE.ini] [--nav-config FILE.ini]\n"
    "                [--view [--screenshot F.png]] [--navigate X,Y] [--frames N]\n"
    "                [--output DIR] [--record RUN.rawlog]\n"
    "                [--stale-timeout S] [--mount FILE.ini | --auto-mount] [--base sim|ros]\n"
    "  Reads a live source, runs the UPD and the traversability map on every frame and, with\n"
    "  --navigate, drives the robot base to the goal with MRPT's reactive navigator. The shipped\n"
    "  base is simulated (it moves on the velocity commands, the camera does not): see\n"
    "  docs/NAVIGATION.md to plug in a real one. Ctrl-C stops. Devices and routes:\n"
    "  docs/SENSORS.md.\n\n"
    "SOURCE (one of; default: the first OpenNI2 device):\n"
    "  --oni FILE.oni         an OpenNI2 recording (OpenNI2 devices: Xtion, Carmine, PS1080)\n"
    "  --kinect [INDEX]       a Kinect v1 through libfreenect (default index 0)\n"
    "  --sensors FILE.ini     a sensor section of an MRPT rawlog-grabber file (stereo cameras,\n"
    "                         Velodyne, COpenNI2Sensor, image folders, rawlogs, ...)\n"
    "  --sensor-section NAME  its section, when the file has several\n\n"
    "options:\n"
    "  --config FILE      robot config (default config/dune-kinect.ini)\n"
    "  --nav-config FILE  navigation config: camera mount, obstacles, navigator\n"
    "                     (default config/dune-nav.ini)\n"
    "  --view             3D view: cloud coloured by zeta, the map, the robot, its path and\n"
    "                     the route (the keys of upd view; docs/VIEWER.md)\n"
    "  --screenshot FILE.png  with --view: save what the window shows at the end of the run\n"
    "  --base sim|ros     the base driven: simulated (default) or ROS 1 (/cmd_vel out, /odom\n"
    "                     in; docs/ROS.md)\n"
    "  --navigate X,Y     goal in the map frame (the robot starts at 0,0 facing +x) [m]\n"
    "  --frames N         stop after N frames (default: until the end, the goal or Ctrl-C)\n"
    "  --output DIR       write map.png, map.pgm + map.yaml, summary.json and the navlog\n"
    "                     (with --navigate) at the end\n"
    "  --record RUN.rawlog  write every observation and the base's odometry as an MRPT rawlog\n"
    "                     (RUN.rawlog.part while running, renamed at the end; `upd playback`\n"
    "                     replays it)\n"
    "  --stale-timeout S  the source counts as stopped when no new frame came for S seconds\n"
    "                     (default 1): the robot is stopped and the run ends\n"
    "  --mount FILE.ini   camera mount [CameraMountParams] over the nav config's (as written\n"
    "                     by upd calibrate-mount --output); applies to every source\n"
    "  --auto-mount       measure the mount from the floor in the first frames (robot on a\n"
    "                     level floor); no floor found: one line, exit status 1, no run\n\n"
    "exit status: 0 done; 1 error (a source that cannot be opened, ...), or a recording that\n"
    "stopped (a full disk) while the run went on; 2 usage error; 3 --navigate did not reach the\n"
    "goal; 4 the source stopped (the robot was stopped); 5 the robot base stopped answering (an\n"
    "emergency stop was sent). --output is written whenever the run took place.\n";

namespace {

using Clock = std::chrono::steady_clock;
constexpr int kExitSourceStopped = 4;
constexpr int kExitBaseFault = 5;

/// What one run did, for the summary line and summary.json.
struct LiveTally {
  std::string source, end;
  int frames = 0;
  double seconds = 0;
  double score_ms = 0;  ///< summed over the frames
  std::map<std::string, std::size_t> skipped;  ///< observations that gave no cloud, by reason
  std::optional<SourceStall> stall;
  std::optional<BaseFault> base_fault;
  std::size_t recorded = 0;  ///< the observations handed to the recording
  std::size_t saved = 0;     ///< those of them in its file's complete members
  std::string record_error;  ///< why the recording stopped early ("" when it did not)
  nav::NavOutcome outcome;
};

void printSummary(const LiveTally& t, const maps::GridStats& stats) {
  std::printf("%s: %d frames in %.1f s (%.1f Hz), map %zu known cells (%zu non-traversable)\n",
              t.end.c_str(), t.frames, t.seconds, t.seconds > 0 ? t.frames / t.seconds : 0.0,
              stats.known, stats.non_traversable);
  for (const auto& [reason, n] : t.skipped) std::printf("  skipped %zu: %s\n", n, reason.c_str());
  if (!t.outcome.error_code.empty()) {
    std::printf("  navigator: %s %s: %s\n", nav::toString(t.outcome.state),
                t.outcome.error_code.c_str(), t.outcome.error_message.c_str());
  }
}

nlohmann::json stallJson(const SourceStall& s, double timeout_s) {
  return {{"detected_at_s", s.at_s},     {"silent_s", s.silent_s},
          {"timeout_s", timeout_s},      {"new_frames", s.new_frames},
          {"stale_frames", s.stale_frames}, {"robot_stopped", s.robot_stopped},
          {"message", s.line()}};
}

// map.png, map.pgm + map.yaml and summary.json in dir.
void writeLiveOutputs(const std::string& dir, const LiveOptions& o, const LiveTally& t,
                      const maps::TraversabilityGrid& grid, const maps::GridStats& stats) {
  namespace fs = std::filesystem;
  OutputFolder folder(dir);  // removed again, if empty, when a file cannot be written
  maps::writeColourPng(grid, (fs::path(dir) / "map.png").string());
  maps::writeRosMap(grid, (fs::path(dir) / "map").string());
  nlohmann::json j;
  j["upd_nav_version"] = core::version();
  j["source"] = t.source;
  j["end"] = t.end;
  j["frames"] = t.frames;
  j["seconds"] = t.seconds;
  j["mean_frame_scoring_ms"] = t.frames > 0 ? t.score_ms / t.frames : 0.0;
  j["frames_skipped"] = nlohmann::json::object();
  for (const auto& [reason, n] : t.skipped) j["frames_skipped"][reason] = n;
  j["map_known_cells"] = stats.known;
  j["map_non_traversable_cells"] = stats.non_traversable;
  j["source_stopped"] = t.stall ? stallJson(*t.stall, o.stale_timeout_s) : nlohmann::json();
  j["base_fault"] = nlohmann::json();
  if (t.base_fault) {
    j["base_fault"] = {{"reason", t.base_fault->reason},
                       {"frames", t.base_fault->frames},
                       {"robot_stopped", t.base_fault->robot_stopped},
                       {"message", t.base_fault->line()}};
  }
  if (o.record) {
    const bool whole = t.record_error.empty();
    j["recording"] = {{"path", whole ? *o.record : *o.record + ".part"},
                      {"observations", t.saved},
                      {"observations_handed", t.recorded},
                      {"error", whole ? nlohmann::json() : nlohmann::json(t.record_error)}};
  }
  if (o.goal) {
    j["goal_xy_m"] = {o.goal->x(), o.goal->y()};
    j["navigator"] = {{"state", nav::toString(t.outcome.state)},
                      {"target_reached_event", t.outcome.target_reached},
                      {"error_code", t.outcome.error_code},
                      {"error_message", t.outcome.error_message}};
  }
  io::writeJsonAtomically((fs::path(dir) / "summary.json").string(), j);
  folder.keep();
  std::printf("  outputs in %s\n", dir.c_str());
}

// The robot, the navigation loop, the view and the recording of one run, and its counters.
struct LiveRun {
  LiveRun(const LiveOptions& o, const nav::NavConfig& c, const mrpt_bridge::SourceParams& sp)
      : opt(o),
        config(c),
        source_params(sp),
        base({}, c.base),
        external(makeLiveBase(o.base)),
        loop(external ? *external : base, c, nav::ObstacleDetector::Upd,
             o.out && o.goal
                 ? (std::filesystem::path(*o.out) / "navigation.reactivenavlog").string()
                 : "") {
    if (o.view) view = std::make_unique<LiveView>("upd live", c.body);
    if (o.record) recorder.emplace(*o.record);
    if (o.goal) loop.navigateTo(*o.goal);
    t0 = last = last_report = now = Clock::now();  // the run starts after the set-up
  }
  /// The base driven: the real one when there is one.
  nav::RobotBase& driven() { return external ? *external : base; }
  double secondsSinceStart() const {
    return std::chrono::duration<double>(Clock::now() - t0).count();
  }

  const LiveOptions& opt;
  const nav::NavConfig& config;
  const mrpt_bridge::SourceParams& source_params;
  nav::SimulatedDiffDrive base;
  std::unique_ptr<nav::RobotBase> external;  ///< a real base (--base ros), else nullptr
  nav::NavigationLoop loop;
  std::unique_ptr<LiveView> view;
  std::optional<mrpt_bridge::RawlogWriter> recorder;
  mrpt_bridge::ObservationCloud converted;  ///< reused frame to frame
  Clock::time_point t0, last, last_report, now;
  int frames = 0;
  double score_ms = 0;
  std::map<std::string, std::size_t> skipped;
  std::optional<BaseFault> base_fault;  ///< set when the base stopped answering
  std::string record_error;             ///< why the recording stopped (the run went on)
  std::size_t recorded = 0;             ///< the observations handed to the recording
  std::size_t saved = 0;                ///< those of them in its file's complete members
};

// A recording that fails (a full disk) stops, as rosbag's does, and the run goes on: one line
// now, exit status 1 at the end. The .part file keeps what was written up to its last flush.
void stopRecording(LiveRun& run, const std::string& error) {
  run.recorded = run.recorder->written();
  run.saved = run.recorder->saved();  // (final: a failed writer writes nothing more)
  run.record_error = error;
  run.recorder.reset();  // (what is queued is dropped by the failed writer; the file closed)
  std::fprintf(stderr, "upd live: recording stopped: %s; the run goes on\n", error.c_str());
}

// The base's pose at the frame (before it) and the observation, into the recording.
void recordFrame(LiveRun& run, const mrpt::obs::CObservation& obs, const nav::BaseState& s) {
  if (!run.recorder) return;
  const double t = obs.timestamp == INVALID_TIMESTAMP ? mrpt::Clock::toDouble(mrpt::Clock::now())
                                                       : mrpt::Clock::toDouble(obs.timestamp);
  try {
    run.recorder->writeOdometry(s.pose_world_robot.x_m, s.pose_world_robot.y_m,
                                s.pose_world_robot.yaw_rad, t);
    run.recorder->write(obs);
  } catch (const std::runtime_error& e) {
    stopRecording(run, e.what());
  }
}

// Scores one observation into the map at the base's pose, advanced to the frame's arrival;
// nullptr (counted) when the observation gives no cloud, or (run.base_fault set, the robot told
// to stop) when the base does not answer.
const nav::FrameEvidence* addFrame(LiveRun& run, mrpt::obs::CObservation& obs,
                                   nav::BaseState& s) {
  if (run.opt.mount || run.opt.auto_mount) remount(obs, run.config.camera);
  run.now = Clock::now();
  const double dt = std::chrono::duration<double>(run.now - run.last).count();
  run.last = run.now;
  if (dt > 0 && !run.external) run.base.advance(dt);
  nav::RobotBase& driven = run.driven();
  run.base_fault = readBaseState(driven, static_cast<std::size_t>(run.frames), s);
  if (run.base_fault) return nullptr;
  recordFrame(run, obs, s);
  mrpt_bridge::toCloud(obs, run.source_params, run.converted);
  if (!run.converted.ok()) {
    ++run.skipped[run.converted.skipped_reason];
    return nullptr;
  }
  const Eigen::Vector3d xy_yaw(s.pose_world_robot.x_m, s.pose_world_robot.y_m,
                               s.pose_world_robot.yaw_rad);
  const core::PointCloud cloud_world =
      core::transformCloud(run.converted.cloud_in_robot, sim::bodyPoseFlat(xy_yaw));
  const nav::FrameEvidence& ev = run.loop.addFrame(cloud_world, driven.timeS());
  run.score_ms += ev.timings.total_ms;
  ++run.frames;
  return &ev;
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
    run.view->show(ev, run.loop.grid(), s.pose_world_robot,
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

// Frames until the limit, the end of a recording, the goal, the window closing, a signal or
// the source stopping (then the robot is stopped and t.stall says so).
std::string runFrames(LiveRun& run, LiveSource& source, LiveTally& t) {
  SourceWatchdog watchdog(run.opt.stale_timeout_s, 0.0);
  const std::function<double()> now_s = [&run] { return run.secondsSinceStart(); };
  LiveFrame frame;
  while (true) {
    if (run.opt.max_frames > 0 && run.frames >= run.opt.max_frames) return "frame limit";
    SourceStall stall;
    switch (nextFreshFrame(source, watchdog, run.driven(), now_s, stopRequested, frame, stall)) {
      case NextFrame::End:
        return "end of the recording";
      case NextFrame::Interrupted:
        return "interrupted";
      case NextFrame::Stalled:
        std::fprintf(stderr, "upd live: %s: %s\n", source.description().c_str(),
                     stall.line().c_str());
        t.stall = stall;
        return "source stopped";
      case NextFrame::Fresh:
        break;
    }
    nav::BaseState s;
    const nav::FrameEvidence* ev = addFrame(run, *frame.observation, s);
    if (run.base_fault) {
      std::fprintf(stderr, "upd live: %s\n", run.base_fault->line().c_str());
      t.base_fault = run.base_fault;
      return "base stopped answering";
    }
    if (!ev) continue;
    if (const auto end = afterFrame(run, *ev, s)) return *end;
    reportProgress(run, *ev, s);
  }
}

// The summary line, the outputs and the exit status of a run.
int finishLive(const LiveOptions& o, const LiveTally& t, const maps::TraversabilityGrid& grid) {
  const auto stats = maps::computeStats(grid);
  printSummary(t, stats);
  if (o.record && t.record_error.empty()) {
    std::printf("  recorded %zu observations to %s\n", t.recorded, o.record->c_str());
  } else if (o.record) {
    std::fprintf(stderr,
                 "upd live: error: the recording stopped: %s; %s.part holds the first %zu of the "
                 "%zu observations the run gave it\n",
                 t.record_error.c_str(), o.record->c_str(), t.saved, t.recorded);
  }
  if (o.out) writeLiveOutputs(*o.out, o, t, grid, stats);
  if (t.base_fault) return kExitBaseFault;
  if (t.stall) return kExitSourceStopped;
  if (o.goal && !t.outcome.target_reached) return 3;
  return t.record_error.empty() ? 0 : 1;
}

// `--auto-mount`: the mount measured from the floor in the source's first frames; throws (no
// run) when they show no floor or the source ends or stops first.
sim::CameraMountParams autoMountFromSource(LiveSource& source, const LiveOptions& o,
                                           const sim::CameraMountParams& configured) {
  const auto t0 = Clock::now();
  const auto next = [&](core::PointCloud& cloud) {
    LiveFrame frame;
    while (!stopRequested()) {
      const double waited = std::chrono::duration<double>(Clock::now() - t0).count();
      if (waited > o.stale_timeout_s * (kAutoMountFrames + 1)) return false;
      const Poll p = source.poll(frame);
      if (p == Poll::End) return false;
      if (p == Poll::Frame && opticalFrameCloud(*frame.observation, cloud)) return true;
    }
    return false;
  };
  return autoMount(next, configured, kAutoMountFrames);
}

// Runs the source through the loop until it stops.
int runSource(const LiveOptions& o, nav::NavConfig config, const RunConfig& run_config) {
  const auto source =
      openLiveSource(o, sim::mountOnRobot(config.camera), config.camera.image_downscale);
  std::printf("source: %s\n", source->description().c_str());
  if (o.auto_mount) config.camera = autoMountFromSource(*source, o, config.camera);  // or no run
  LiveRun run(o, config, run_config.observer.source);
  LiveTally t;
  t.source = source->description();
  {
    const StopOnSignal stop_on_signal;
    t.end = runFrames(run, *source, t);
    if (stopRequested()) t.end = "interrupted";
    t.outcome = run.loop.outcome();
    run.loop.finish();
  }
  if (run.recorder) {
    try {
      run.recorded = run.recorder->written();
      run.recorder->finish();
      run.saved = run.recorder->saved();
    } catch (const std::runtime_error& e) {
      stopRecording(run, e.what());
    }
  }
  t.recorded = run.recorded;
  t.saved = run.saved;
  t.record_error = run.record_error;
  if (run.view && o.screenshot && run.view->isOpen()) {
    run.view->saveScreenshot(*o.screenshot);
    std::printf("  screenshot %s\n", o.screenshot->c_str());
  }
  t.seconds = run.secondsSinceStart();
  t.frames = run.frames;
  t.score_ms = run.score_ms;
  t.skipped = run.skipped;
  return finishLive(o, t, run.loop.grid().wholeRun());  // the map of the whole run
}

}  // namespace

int runLive(const std::vector<std::string>& argv) {
  const LiveOptions o = parseLiveOptions(argv);
  // The shared robot config, checked strictly as every command does; its [SourceParams] say
  // how observations become clouds.
  const RunConfig run_config = loadRunConfig(o.config_path);
  nav::NavConfig config = nav::loadNavConfig(o.config_path, o.nav_path);
  if (o.mount) loadMountFile(*o.mount, config.camera);
  if (o.view && !nav::displayAvailable()) {
    throw std::runtime_error("--view needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set)");
  }
  return runSource(o, config, run_config);
}

}  // namespace upd::app
