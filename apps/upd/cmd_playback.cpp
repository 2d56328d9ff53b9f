// `upd playback`: replays a rawlog through the UPD observer, fuses every frame into the 2.5D
// traversability grid and the OctoMap tree, and exports them (PNG with legend, ROS map_server
// PGM + YAML, .ot/.bt, .3Dscene, optional per-frame PLY and an annotated rawlog) with a
// summary.json. A ground-truth grid next to the rawlog (as `upd simulate` writes it) is used
// to score the map (maps::evaluateGrid). A damaged rawlog keeps the maps of its good frames and
// exits kExitPartial (playback_damage.h), as does a run stopped by Ctrl-C or SIGTERM after the
// frame in progress (stop_signal.h).
#include "calibrate_mount.h"
#include "cli.h"
#include "commands.h"
#include "map_folder.h"
#include "output_folder.h"
#include "playback_bag.h"
#include "playback_damage.h"
#include "playback_merge.h"
#include "playback_tum.h"
#include "playback_view.h"
#include "run_config.h"
#include "whole_run.h"
#include "stop_signal.h"

#include "upd/core/stopwatch.h"
#include "upd/core/version.h"
#include "upd/gdal/geotiff.h"
#include "upd/io/atomic_file.h"
#include "upd/io/cloud_io.h"
#include "upd/io/json_io.h"
#include "upd/io/ros_map.h"
#include "upd/maps/evaluation.h"
#include "upd/maps/grid_export.h"
#include "upd/maps/grid_fusion.h"
#include "upd/mrpt_bridge/gz_output_stream.h"
#include "upd/mrpt_bridge/rawlog_reader.h"
#include "upd/mrpt_bridge/simulated_run.h"

#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/serialization/CArchive.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <ostream>
#include <unistd.h>

namespace upd::app {

const char* const kPlaybackUsage =
    "usage: upd playback RAWLOG...|TUM_DIR|RUN.bag --config FILE.ini --output DIR [options]\n"
    "  Replays RAWLOG (either rawlog layout): UPD for every 3D observation in the world frame,\n"
    "  fused over time into a 2.5D traversability grid and an OctoMap tree; several RAWLOGs\n"
    "  (runs of one site in one world frame) are fused one after the other into one map.\n"
    "  Writes into DIR: map.png (colour, with legend), map.pgm + map.yaml (ROS map_server,\n"
    "  trinary), map_cost.pgm + map_cost.yaml (ROS, graded: mode scale), map.tif (GeoTIFF, one\n"
    "  band per layer, for GIS tools), map.ot (OctoMap\n"
    "  ColorOcTree coloured by traversability, for every OctoMap tool; map_colour.ot is the same\n"
    "  file), map_traversability.ot (the full tree, read with upd::maps::readTraversabilityOt),\n"
    "  map.bt (occupancy), map.3Dscene (MRPT SceneViewer3D) and summary.json.\n"
    "  A ROS 1 bag (depth Image + CameraInfo or PointCloud2, tf for the poses; on its own) is\n"
    "  first converted to DIR/bag.rawlog and DIR/bag_poses.tum (docs/ROS.md).\n\n"
    "options:\n"
    "  --config FILE.ini   robot/sensor parameters (config/dune-kinect.ini, ...) (required)\n"
    "  --output DIR        output directory, created if missing (required)\n"
    "  --from N --to M     observations N..M only (0-based, inclusive)\n"
    "  --every K           every K-th observation\n"
    "  --poses FILE.tum    robot poses from a ground-truth file (TUM: t x y z qx qy qz qw)\n"
    "                      instead of the rawlog's odometry; with several RAWLOGs one file\n"
    "                      per rawlog, comma-separated (A.tum,B.tum)\n"
    "  --epsg CODE         the poses are in this projected CRS (e.g. 32633: UTM 33N easting/\n"
    "                      northing [m]); map.tif carries it\n"
    "  --truth FILE.yaml   ground-truth traversability grid to score the map against\n"
    "                      (default: RAWLOG's .truth.yaml sidecar when present)\n"
    "  --mount FILE.ini    put the camera on this [CameraMountParams] (upd calibrate-mount\n"
    "                      --output) instead of the recorded sensor pose\n"
    "  --ply               also write every frame's scored cloud as DIR/frames/NNNNNN.ply\n"
    "  --output-rawlog     also write DIR/annotated.rawlog: each frame with its non-traversable\n"
    "                      points as a CObservationPointCloud (label UPD_NON_TRAVERSABLE)\n"
    "  --strict            a damaged rawlog is an error (exit 1, nothing written) instead of\n"
    "                      a partial run\n"
    "  --quiet             no progress line\n"
    "  --view              show the frames and the map in a 3D window as they are played\n"
    "                      (upd view's window and keys; needs a display); kept open at the end\n\n"
    "A damaged rawlog (cut off, or an object that does not deserialize) is played up to the\n"
    "damage: the maps of the observations before it are written, summary.json records the\n"
    "damage (object index, byte offset in the decompressed stream, reason) and one line on\n"
    "stderr names it. Damage before the first observation writes nothing.\n\n"
    "TUM RGB-D folder: upd playback DIR ... plays DIR/depth.txt's 16-bit depth PNGs (5000 per m)\n"
    "with the camera poses of DIR/groundtruth.txt (a z-up world), written as DIR_OUT/sequence\n"
    ".rawlog first. Its options: --intrinsics F.yaml (OpenCV/ROS YAML) or --tum-camera\n"
    "freiburg1|freiburg2|freiburg3|ros (default: the freiburgN in DIR's name), --depth-scale S\n"
    "(metres per unit, default 0.0002), --poses FILE instead of groundtruth.txt.\n\n"
    "Ctrl-C (SIGINT) or SIGTERM stops after the frame in progress: the maps of the frames\n"
    "processed so far are written and summary.json says \"end\": \"interrupted\" (a second\n"
    "Ctrl-C ends at once, writing nothing more).\n\n"
    "exit status: 0 done; 1 failed, nothing written; 2 usage error; 3 partial: the rawlog is\n"
    "damaged (not with --strict) or the run was interrupted, and the maps of the frames\n"
    "processed were written.\n";

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

struct PlaybackOptions {
  std::string rawlog;                ///< the run being played (the first one until then)
  std::vector<std::string> rawlogs;  ///< every RAWLOG given, fused into one map
  std::string config_path;
  fs::path out_dir;
  long from = 0, to = -1, every = 1;  ///< to < 0: to the end
  std::optional<std::string> poses_path;
  std::optional<std::string> truth_path;
  int epsg = 0;  ///< CRS of map.tif (0: none)
  std::optional<sim::CameraMountParams> mount;  ///< --mount: replaces the recorded sensor pose
  bool ply = false, output_rawlog = false, quiet = false, strict = false, view = false;

  /// Entry idx is inside --from/--to/--every.
  bool selected(long idx) const {
    return idx >= from && (to < 0 || idx <= to) && (idx - from) % every == 0;
  }
};

PlaybackOptions parsePlaybackOptions(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--config", "--output", "--from", "--to", "--every", "--poses", "--truth",
                   "--epsg", "--mount"},
                  {"--ply", "--output-rawlog", "--quiet", "--strict", "--view"});
  if (args.positionals().empty()) throw UsageError("expected at least one RAWLOG");
  if (!args.has("--config")) throw UsageError("--config FILE.ini is required");
  if (!args.has("--output")) throw UsageError("--output DIR is required");
  PlaybackOptions o;
  o.rawlogs = args.positionals();
  o.rawlog = o.rawlogs[0];
  o.config_path = *args.str("--config");
  o.out_dir = *args.str("--output");
  o.from = args.integer("--from").value_or(0);
  o.to = args.integer("--to").value_or(-1);
  o.every = args.integer("--every").value_or(1);
  if (o.from < 0) throw UsageError("option --from = " + std::to_string(o.from) + ": must be >= 0");
  if (o.every < 1) {
    throw UsageError("option --every = " + std::to_string(o.every) + ": must be >= 1");
  }
  if (o.to >= 0 && o.to < o.from) {
    throw UsageError("option --to = " + std::to_string(o.to) + ": before --from");
  }
  o.poses_path = args.str("--poses");
  o.truth_path = args.str("--truth");
  o.epsg = args.integer("--epsg").value_or(0);
  if (const auto m = args.str("--mount")) loadMountFile(*m, o.mount.emplace());
  o.ply = args.flag("--ply");
  o.output_rawlog = args.flag("--output-rawlog");
  o.quiet = args.flag("--quiet");
  o.strict = args.flag("--strict");
  o.view = args.flag("--view");
  return o;
}

// The ground truth: --truth, else the rawlog's sidecar when present; none without either.
struct Truth {
  std::string path;
  std::optional<io::RosMap> grid;
};

Truth loadTruth(const PlaybackOptions& o) {
  Truth t;
  t.path = o.truth_path.value_or("");
  if (t.path.empty() && fs::exists(mrpt_bridge::truthMapPath(o.rawlog))) {
    t.path = mrpt_bridge::truthMapPath(o.rawlog);
  }
  if (!t.path.empty()) t.grid = io::readRosMap(t.path);
  return t;
}

json scoresJson(const maps::MapEvaluation& e) {
  auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  return {{"precision", num(e.precision())},
          {"recall", num(e.recall())},
          {"map_non_traversable_cells", e.map_non_traversable},
          {"truth_non_traversable_cells_observed", e.truth_non_traversable}};
}

// The grid scored against the truth at tolerance_m and cell by cell.
json truthJson(const maps::TraversabilityGrid& grid, const Truth& truth, double tolerance_m) {
  const io::RosMap& raster = *truth.grid;
  const maps::TruthLabelAt label_at = [&raster](double x_m, double y_m) {
    return raster.labelAt(x_m, y_m);
  };
  return {{"map", truth.path},
          {"tolerance_m", tolerance_m},
          {"scores", scoresJson(maps::evaluateGrid(grid, label_at, tolerance_m))},
          {"scores_strict", scoresJson(maps::evaluateGrid(grid, label_at, 0.0))}};
}

// The annotated rawlog, written frame by frame to a temporary file that commit() renames over
// the target; without commit() (an error) the temporary file is removed.
class AnnotatedRawlog {
 public:
  explicit AnnotatedRawlog(const std::string& path)
      : path_(path), tmp_(path + ".tmp-" + std::to_string(::getpid())), out_(tmp_) {}
  ~AnnotatedRawlog() {
    if (committed_) return;
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
  AnnotatedRawlog(const AnnotatedRawlog&) = delete;
  AnnotatedRawlog& operator=(const AnnotatedRawlog&) = delete;

  /// The entry's odometry (as an action) and a sensory frame with its observation and the
  /// frame's non-traversable points.
  void write(const mrpt_bridge::RawlogEntry& entry, const Eigen::Isometry3d& pose_world_robot,
             const core::ScoredFrame& scored);
  void commit() {
    out_.close();
    fs::rename(tmp_, path_);
    committed_ = true;
  }

 private:
  std::string path_, tmp_;
  mrpt_bridge::GzOutputStream out_;
  bool committed_ = false;
};

void AnnotatedRawlog::write(const mrpt_bridge::RawlogEntry& entry,
                            const Eigen::Isometry3d& pose_world_robot, const core::ScoredFrame& scored) {
  auto arch = mrpt::serialization::archiveFrom(out_);
  if (entry.odometry_increment) {
    const Eigen::Isometry3d& inc = *entry.odometry_increment;
    mrpt::obs::CActionRobotMovement2D act;
    act.computeFromOdometry(
        mrpt::poses::CPose2D(inc.translation().x(), inc.translation().y(),
                             std::atan2(inc.linear()(1, 0), inc.linear()(0, 0))),
        mrpt::obs::CActionRobotMovement2D::TMotionModelOptions());
    mrpt::obs::CActionCollection acts;
    acts.insert(act);
    arch << acts;
  }
  // Non-traversable points in the robot frame, as RawLogViewer draws observations.
  auto pts = mrpt::maps::CSimplePointsMap::Create();
  const Eigen::Isometry3d robot_world = pose_world_robot.inverse();
  for (std::size_t i = 0; i < scored.size(); ++i) {
    if (scored.classes.label[i] != core::Label::NonTraversable) continue;
    const Eigen::Vector3d p = robot_world * scored.cloud_world.point(i).cast<double>();
    pts->insertPoint(static_cast<float>(p.x()), static_cast<float>(p.y()),
                     static_cast<float>(p.z()));
  }
  auto pc = mrpt::obs::CObservationPointCloud::Create();
  pc->pointcloud = pts;
  pc->sensorLabel = "UPD_NON_TRAVERSABLE";
  pc->timestamp = entry.observation->timestamp;
  mrpt::obs::CSensoryFrame sf;
  sf.insert(entry.observation);
  sf.insert(pc);
  arch << sf;
}

void writeFramePly(const fs::path& path, const core::ScoredFrame& scored) {
  io::ScoredPoints sp;
  const auto& c = scored.cloud_world;
  sp.x = c.x, sp.y = c.y, sp.z = c.z;
  sp.nx = scored.normals_world.nx, sp.ny = scored.normals_world.ny;
  sp.nz = scored.normals_world.nz;
  sp.rx = scored.upd.rx, sp.ry = scored.upd.ry, sp.rz = scored.upd.rz;
  sp.zeta = scored.upd.zeta;
  sp.label = scored.classes.label;
  sp.cost = scored.classes.cost;
  if (c.hasColor()) sp.r = c.r, sp.g = c.g, sp.b = c.b;
  io::writeScoredPly(path.string(), sp);
}

// Progress on a terminal: frames done, frames/s and the time left.
class Progress {
 public:
  Progress(bool enabled, std::size_t total) : enabled_(enabled && ::isatty(2)), total_(total) {}
  void update(std::size_t done) {
    if (!enabled_) return;
    const double s = clock_.elapsedMs() / 1000.0;
    const double fps = s > 0 ? done / s : 0;
    std::fprintf(stderr, "\r  frame %zu/%zu  %.1f frames/s  ETA %.0f s   ", done, total_, fps,
                 fps > 0 && total_ > done ? (total_ - done) / fps : 0.0);
  }
  void finish() {
    if (enabled_) std::fprintf(stderr, "\n");
  }

 private:
  bool enabled_;
  std::size_t total_;
  core::Stopwatch clock_;
};

// Sums over the processed frames [ms], reported per frame in summary.json.
struct StageSums {
  double convert = 0, preprocess = 0, normals = 0, upd = 0, classify = 0, grid = 0, octree = 0,
         frame_total = 0;

  json perFrame(double frames) const {
    return {{"convert", convert / frames},     {"preprocess", preprocess / frames},
            {"normals", normals / frames},     {"upd", upd / frames},
            {"classify", classify / frames},   {"grid", grid / frames},
            {"octree", octree / frames},       {"frame_total", frame_total / frames}};
  }
};

// What the frame loop builds: the maps and the run's counts and timings.
struct Playback {
  maps::TraversabilityGrid grid;
  maps::TraversabilityOcTree tree;
  std::map<std::string, std::size_t> skipped;
  std::vector<Eigen::Vector3d> trajectory;
  StageSums sums;
  std::vector<double> frame_ms;
  std::size_t read = 0, processed = 0, points_scored = 0;
  std::string pose_source;  ///< where the robot poses came from
  std::optional<RawlogDamage> damage;  ///< set when the rawlog ended in damage (not --strict)
  int interrupted_by = 0;  ///< the signal that stopped the frame loop early, 0 if none
  MemoryTrace memory_trace;  ///< resident memory every 1,000 frames processed
  std::unique_ptr<PlaybackView> view;  ///< --view

  explicit Playback(const RunConfig& config) : grid(config.grid), tree(config.octree) {}
};

// Fuses one scored frame into the grid and the tree and adds up its timings.
void fuseFrame(const RunConfig& config, const mrpt_bridge::RawlogEntry& entry,
               const mrpt_bridge::ObserverResult& res, const core::Stopwatch& frame_clock,
               Playback& run) {
  const core::ScoredFrame& scored = res.scored;
  const auto view = maps::viewPoints(scored.cloud_world, scored.classes, &scored.upd);
  const double t_s = std::isfinite(entry.timestamp_s) ? entry.timestamp_s
                                                      : static_cast<double>(entry.index);
  const Eigen::Vector2d robot_xy = res.pose_world_robot.translation().head<2>();
  core::Stopwatch stage;
  maps::integrateScan(run.grid, view, robot_xy, t_s, config.fusion);
  const double grid_ms = stage.elapsedMs();
  stage.restart();
  maps::insertScan(run.tree, view, res.pose_world_sensor.translation(), config.octree,
                   config.fusion);
  const double octree_ms = stage.elapsedMs();
  const double total_ms = frame_clock.elapsedMs();

  const core::StageTimings& tm = scored.timings.stages;
  StageSums& s = run.sums;
  s.convert += res.convert_ms;
  s.preprocess += tm.preprocess_ms;
  s.normals += tm.index_ms + tm.normals_ms;
  s.upd += tm.upd_ms;
  s.classify += tm.classify_ms;
  s.grid += grid_ms;
  s.octree += octree_ms;
  s.frame_total += total_ms;
  run.frame_ms.push_back(total_ms);
  run.trajectory.push_back(res.pose_world_robot.translation());
  run.points_scored += res.size() - scored.upd.invalid;
}

// Poses from --poses (a TUM ground truth), else from the rawlog's odometry.
mrpt_bridge::RobotPoseTracker poseTracker(const PlaybackOptions& o, const RunConfig& config) {
  if (!o.poses_path) return {};
  return mrpt_bridge::RobotPoseTracker(mrpt_bridge::TumTrajectory::load(*o.poses_path),
                                      config.ground_truth);
}

// Observations in the rawlog (for the progress line): those before the damage in a damaged one.
std::size_t countEntries(const std::string& rawlog) {
  mrpt_bridge::RawlogReader reader(rawlog);
  mrpt_bridge::RawlogEntry entry;
  try {
    while (reader.next(entry)) {
    }
  } catch (const mrpt_bridge::RawlogError&) {
  }
  return reader.stats().entries;
}

// reader.next(), where damage ends the run as the end of the file would (recorded in
// run.damage), unless strict or nothing was read before it: then it stays an error.
bool nextIntact(mrpt_bridge::RawlogReader& reader, mrpt_bridge::RawlogEntry& entry, bool strict,
                Playback& run) {
  try {
    return reader.next(entry);
  } catch (const mrpt_bridge::RawlogError& err) {
    if (strict || reader.stats().entries == 0) throw;
    run.damage = damageOf(err, reader.stats().entries);
    return false;
  }
}

// Reads every entry, scores the selected ones with a pose and fuses them into the maps.
void playFrames(const PlaybackOptions& o, const RunConfig& config,
                mrpt_bridge::RobotPoseTracker& tracker, Playback& run) {
  mrpt_bridge::RawlogReader reader(o.rawlog);  // throws naming the file when missing
  const std::size_t total = (!o.quiet && ::isatty(2)) ? countEntries(o.rawlog) : 0;
  const mrpt_bridge::UpdObserver observer(config.observer);
  std::optional<AnnotatedRawlog> annotated;
  if (o.output_rawlog) annotated.emplace((o.out_dir / "annotated.rawlog").string());
  Progress progress(!o.quiet, total);

  mrpt_bridge::RawlogEntry entry;
  mrpt_bridge::ObserverResult res;  // reused frame to frame
  while (!stopRequested() && nextIntact(reader, entry, o.strict, run)) {
    ++run.read;
    // Every entry updates the pose tracker, so odometry between selected frames is kept.
    const mrpt_bridge::RobotPose pose = tracker.update(entry);
    const long idx = static_cast<long>(entry.index);
    if (!o.selected(idx)) {
      ++run.skipped["outside --from/--to/--every"];
      continue;
    }
    if (!pose.valid()) {
      ++run.skipped[pose.missing_reason];
      continue;
    }
    const core::Stopwatch frame_clock;
    if (o.mount) remount(*entry.observation, *o.mount);
    observer.observe(*entry.observation, pose.pose_world_robot, res);
    if (!res.ok()) {
      ++run.skipped[res.skipped_reason];
      continue;
    }
    fuseFrame(config, entry, res, frame_clock, run);
    if (run.view) run.view->show(res.scored, run.grid, run.tree, run.trajectory);
    if (o.ply) {
      char name[32];
      std::snprintf(name, sizeof name, "%06ld.ply", idx);
      writeFramePly(o.out_dir / "frames" / name, res.scored);
    }
    if (annotated) annotated->write(entry, pose.pose_world_robot, res.scored);
    ++run.processed;
    run.memory_trace.frameProcessed(run.processed, run.grid, run.tree);
    progress.update(run.read);
  }
  progress.finish();
  run.interrupted_by = stopSignal();
  if (annotated) annotated->commit();
  for (const auto& [reason, n] : reader.stats().skipped) run.skipped[reason] += n;
  run.pose_source = mrpt_bridge::toString(tracker.kind());
}

json summaryJson(const PlaybackOptions& o, const RunConfig& config, Playback& run,
                 const Truth& truth, double wall_time_s) {
  json summary;
  summary["rawlog"] = o.rawlog;
  summary["config"] = o.config_path;
  summary["frames_read"] = run.read;
  summary["frames_processed"] = run.processed;
  json skipped_json = json::object();
  for (const auto& [reason, n] : run.skipped) skipped_json[reason] = n;
  summary["frames_skipped"] = skipped_json;
  summary["pose_source"] = run.pose_source;
  summary["points_scored"] = run.points_scored;
  json per_frame = run.sums.perFrame(run.processed ? double(run.processed) : 1.0);
  std::sort(run.frame_ms.begin(), run.frame_ms.end());
  per_frame["frame_median"] = run.frame_ms.empty() ? 0.0 : run.frame_ms[run.frame_ms.size() / 2];
  summary["timing_ms_per_frame"] = per_frame;
  summary["wall_time_s"] = wall_time_s;
  summary["grid"] = gridJson(run.grid);
  summary["octree"] = octreeJson(run.tree);
  summary["end"] = run.interrupted_by ? "interrupted" : run.damage ? "damaged" : "complete";
  if (run.damage) summary["damage"] = damageJson(*run.damage);
  if (truth.grid) {
    summary["ground_truth"] = truthJson(run.grid, truth, config.evaluation.tolerance_m);
  }
  if (o.rawlogs.size() > 1) summary["rawlogs"] = o.rawlogs;
  if (o.epsg != 0) summary["epsg"] = o.epsg;
  summary["outputs"] = mapFileNames();
  summary["upd_nav_version"] = core::version();
  return summary;
}

void printSummary(const PlaybackOptions& o, const json& summary, double tolerance_m) {
  std::printf("%s: %zu frames read, %zu processed (median %.1f ms/frame); map: %zu known cells, "
              "%zu non-traversable -> %s\n",
              o.rawlog.c_str(), summary["frames_read"].get<std::size_t>(),
              summary["frames_processed"].get<std::size_t>(),
              summary["timing_ms_per_frame"]["frame_median"].get<double>(),
              summary["grid"]["known"].get<std::size_t>(),
              summary["grid"]["non_traversable"].get<std::size_t>(), o.out_dir.string().c_str());
  if (summary.contains("ground_truth")) {
    const auto& sc = summary["ground_truth"]["scores"];
    std::printf("  against the ground truth (tolerance %.2f m): precision %s, recall %s\n",
                tolerance_m, sc["precision"].dump().c_str(), sc["recall"].dump().c_str());
  }
}

}  // namespace

int runPlayback(const std::vector<std::string>& argv) {
  if (isTumPlayback(argv)) return runTumPlayback(argv);  // converts, then plays the rawlog
  const core::Stopwatch wall;
  PlaybackOptions options = parsePlaybackOptions(argv);
  const RunConfig config = loadRunConfig(options.config_path);
  for (auto& input : options.rawlogs) {  // a ROS 1 bag becomes a rawlog (playback_bag.h)
    if (const auto bag = convertBagInput(input, options.out_dir)) {
      if (options.rawlogs.size() > 1) throw UsageError("a bag is played on its own: " + input);
      input = options.rawlog = bag->rawlog;
      if (!options.poses_path) options.poses_path = bag->poses;
      if (!options.quiet) std::printf("%s\n", bag->summary.c_str());
    }
  }
  if (options.epsg != 0) gdal::validateEpsg(options.epsg);
  const std::vector<PlaybackRun> runs =
      playbackRuns(options.rawlogs, options.poses_path, options.ply || options.output_rawlog);
  std::vector<PlaybackOptions> per_run(runs.size(), options);
  std::vector<mrpt_bridge::RobotPoseTracker> trackers;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    per_run[k].rawlog = runs[k].rawlog;
    per_run[k].poses_path = runs[k].poses_path;
    trackers.push_back(poseTracker(per_run[k], config));
  }
  // The window first: without a display nothing is written.
  auto view = options.view ? std::make_unique<PlaybackView>(options.rawlog) : nullptr;
  const Truth truth = loadTruth(options);
  OutputFolder out_folder(options.out_dir);  // removed again, if empty, on an error below
  if (options.ply) fs::create_directories(options.out_dir / "frames");

  Playback run(config);
  run.view = std::move(view);
  {
    const StopOnSignal stop_on_signal;  // Ctrl-C ends the frame loop, the maps are written
    for (std::size_t k = 0; k < runs.size() && !run.damage && !stopRequested(); ++k) {
      playFrames(per_run[k], config, trackers[k], run);
    }
  }
  json memory = runMemoryJson(run.grid, run.tree);  // the working set at the end of the run
  switchToWholeRun(run.grid, run.tree);            // every export covers the whole run
  writeMapFiles(run.grid, run.tree, run.trajectory, options.out_dir, options.epsg);
  json summary = summaryJson(options, config, run, truth, wall.elapsedMs() / 1000.0);
  memory["vm_hwm_with_exports_bytes"] = peakResidentBytes();
  memory["trace"] = run.memory_trace.json();
  summary["memory"] = memory;
  io::writeJsonAtomically((options.out_dir / "summary.json").string(), summary);
  out_folder.keep();
  printSummary(options, summary, config.evaluation.tolerance_m);
  if (run.view) run.view->waitUntilClosed();
  if (run.damage) {
    std::fprintf(stderr, "%s\n", damageLine(*run.damage, options.out_dir.string()).c_str());
    return kExitPartial;
  }
  if (run.interrupted_by) {
    std::fprintf(stderr, "upd playback: interrupted by %s after %zu frames read; maps of the %zu "
                 "processed written to %s (partial, exit %d)\n",
                 stopSignalName(run.interrupted_by), run.read, run.processed,
                 options.out_dir.string().c_str(), kExitPartial);
    return kExitPartial;
  }
  return 0;
}

}  // namespace upd::app
