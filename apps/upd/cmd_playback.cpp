// `upd playback`: replays a rawlog through the UPD observer, fuses every frame into the 2.5D
// traversability grid and the OctoMap tree, and exports them (PNG with legend, ROS map_server
// PGM + YAML, .ot/.bt, .3Dscene, optional per-frame PLY and an annotated rawlog) with a
// summary.json. A ground-truth grid next to the rawlog (as `upd simulate` writes it) is used
// to score the map.
#include "cli.h"
#include "commands.h"
#include "run_config.h"

#include "upd/io/cloud_io.h"
#include "upd/io/json_io.h"
#include "upd/io/ros_map.h"
#include "upd/maps/grid_export.h"
#include "upd/maps/grid_fusion.h"
#include "upd/mrpt/rawlog_reader.h"
#include "upd/mrpt/simulated_run.h"

#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/maps/CSimplePointsMap.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CActionRobotMovement2D.h>
#include <mrpt/obs/CObservationPointCloud.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/poses/CPose2D.h>
#include <mrpt/serialization/CArchive.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <unistd.h>

namespace upd::app {

const char* const kPlaybackUsage =
    "usage: upd playback RAWLOG --config FILE.ini --output DIR [options]\n"
    "  Replays RAWLOG (either rawlog layout): UPD for every 3D observation in the world frame,\n"
    "  fused over time into a 2.5D traversability grid and an OctoMap tree. Writes into DIR:\n"
    "  map.png (colour, with legend), map.pgm + map.yaml (ROS map_server), map.ot (OctoMap with\n"
    "  traversability), map.bt (occupancy), map_colour.ot (for octovis), map.3Dscene (MRPT\n"
    "  SceneViewer3D) and summary.json.\n\n"
    "options:\n"
    "  --config FILE.ini   robot/sensor parameters (config/dune-kinect.ini, ...) (required)\n"
    "  --output DIR        output directory, created if missing (required)\n"
    "  --from N --to M     observations N..M only (0-based, inclusive)\n"
    "  --every K           every K-th observation\n"
    "  --poses FILE.tum    robot poses from a ground-truth file (TUM: t x y z qx qy qz qw)\n"
    "                      instead of the rawlog's odometry\n"
    "  --truth FILE.yaml   ground-truth traversability grid to score the map against\n"
    "                      (default: RAWLOG's .truth.yaml sidecar when present)\n"
    "  --ply               also write every frame's scored cloud as DIR/frames/NNNNNN.ply\n"
    "  --output-rawlog     also write DIR/annotated.rawlog: each frame with its non-traversable\n"
    "                      points as a CObservationPointCloud (label UPD_NON_TRAVERSABLE)\n"
    "  --quiet             no progress line\n";

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Writes through a temporary file beside path, then renames: never a half-written output.
template <class F>
void atomicWrite(const std::string& path, F&& write) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  try {
    write(tmp);
    fs::rename(tmp, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw;
  }
}

struct Scores {
  std::size_t map_non_traversable = 0, map_non_traversable_matched = 0;
  std::size_t truth_non_traversable = 0, truth_non_traversable_found = 0;
  double precision() const {
    return map_non_traversable ? double(map_non_traversable_matched) / map_non_traversable : NAN;
  }
  double recall() const {
    return truth_non_traversable ? double(truth_non_traversable_found) / truth_non_traversable
                                 : NAN;
  }
};

// Precision over the map's non-traversable cells, recall over the observed (known) cells that
// the truth marks non-traversable; a match is within tolerance_m (0: the same cell).
Scores scoreAgainstTruth(const maps::TraversabilityGrid& grid,
                         const io::RosMap& truth, double tolerance_m) {
  const int r = static_cast<int>(std::ceil(tolerance_m / grid.cellSize() - 1e-9));
  const int nx = grid.sizeX(), ny = grid.sizeY();
  std::vector<signed char> map_label(static_cast<std::size_t>(nx) * ny, -1), truth_nt(map_label.size(), 0);
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      const auto c = grid.cellCenter(cx, cy);
      truth_nt[cy * nx + cx] = truth.labelAt(c.x(), c.y()) == Label::NonTraversable;
    }
  }
  maps::forEachKnownCell(grid, [&](int cx, int cy, const maps::GridCell& cell) {
    map_label[cy * nx + cx] = maps::labelOf(cell, grid.params()) == Label::NonTraversable;
  });
  auto anyWithin = [&](int cx, int cy, auto&& pred) {
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        const int x = cx + dx, y = cy + dy;
        if (x < 0 || y < 0 || x >= nx || y >= ny) continue;
        if (std::hypot(dx, dy) * grid.cellSize() > tolerance_m + 1e-9) continue;
        if (pred(y * nx + x)) return true;
      }
    }
    return false;
  };
  Scores s;
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      const int i = cy * nx + cx;
      if (map_label[i] < 0) continue;  // never observed
      const auto c = grid.cellCenter(cx, cy);
      if (truth.labelAt(c.x(), c.y()) == Label::Unknown) continue;  // outside the world
      if (map_label[i] == 1) {
        ++s.map_non_traversable;
        s.map_non_traversable_matched += anyWithin(cx, cy, [&](int j) { return truth_nt[j] == 1; });
      }
      if (truth_nt[i]) {
        ++s.truth_non_traversable;
        s.truth_non_traversable_found += anyWithin(cx, cy, [&](int j) { return map_label[j] == 1; });
      }
    }
  }
  return s;
}

json scoresJson(const Scores& s) {
  auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  return {{"precision", num(s.precision())},
          {"recall", num(s.recall())},
          {"map_non_traversable_cells", s.map_non_traversable},
          {"truth_non_traversable_cells_observed", s.truth_non_traversable}};
}

void write3DScene(const maps::TraversabilityGrid& grid,
                  const std::vector<Eigen::Vector3d>& trajectory, const std::string& path) {
  mrpt::opengl::COpenGLScene scene;
  auto plane = mrpt::opengl::CGridPlaneXY::Create(
      static_cast<float>(grid.xMin()), static_cast<float>(grid.xMax()),
      static_cast<float>(grid.yMin()), static_cast<float>(grid.yMax()), 0, 1.0f);
  plane->setColor(0.7, 0.7, 0.7, 0.4);
  scene.insert(plane);
  auto cells = mrpt::opengl::CPointCloudColoured::Create();
  cells->setPointSize(4.0f);
  maps::forEachKnownCell(grid, [&](int cx, int cy, const maps::GridCell& c) {
    const auto xy = grid.cellCenter(cx, cy);
    const auto rgb = maps::traversabilityColourRgb(maps::probabilityOf(c, grid.params()));
    const float z = std::isfinite(c.elevation_m) ? c.elevation_m : 0.f;
    cells->push_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()), z, rgb[0] / 255.f,
                     rgb[1] / 255.f, rgb[2] / 255.f);
  });
  scene.insert(cells);
  auto path_lines = mrpt::opengl::CSetOfLines::Create();
  path_lines->setColor(0.1, 0.2, 0.9);
  path_lines->setLineWidth(3);
  for (std::size_t k = 1; k < trajectory.size(); ++k) {
    const auto& a = trajectory[k - 1];
    const auto& b = trajectory[k];
    path_lines->appendLine(a.x(), a.y(), a.z() + 0.05, b.x(), b.y(), b.z() + 0.05);
  }
  scene.insert(path_lines);
  atomicWrite(path, [&](const std::string& tmp) {
    if (!scene.saveToFile(tmp)) throw std::runtime_error("cannot write " + path);
  });
}

// Progress on a terminal: frames done, frames/s and the time left.
class Progress {
 public:
  Progress(bool enabled, std::size_t total) : enabled_(enabled && ::isatty(2)), total_(total) {}
  void update(std::size_t done) {
    if (!enabled_) return;
    const double s = msSince(start_) / 1000.0;
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
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace

int runPlayback(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--config", "--output", "--from", "--to", "--every", "--poses", "--truth"},
                  {"--ply", "--output-rawlog", "--quiet"});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one RAWLOG");
  const std::string rawlog = args.positionals()[0];
  if (!args.has("--config")) throw UsageError("--config FILE.ini is required");
  if (!args.has("--output")) throw UsageError("--output DIR is required");
  const long from = args.integer("--from").value_or(0);
  const long to = args.integer("--to").value_or(-1);
  const long every = args.integer("--every").value_or(1);
  if (from < 0) throw UsageError("option --from = " + std::to_string(from) + ": must be >= 0");
  if (every < 1) throw UsageError("option --every = " + std::to_string(every) + ": must be >= 1");
  if (to >= 0 && to < from) throw UsageError("option --to = " + std::to_string(to) + ": before --from");

  const RunConfig config = loadRunConfig(*args.str("--config"));
  mrptbridge::RobotPoseTracker tracker;
  if (const auto poses = args.str("--poses")) {
    tracker = mrptbridge::RobotPoseTracker(mrptbridge::TumTrajectory::load(*poses),
                                           config.ground_truth);
  }
  std::optional<io::RosMap> truth;
  std::string truth_path = args.str("--truth").value_or("");
  if (truth_path.empty() && fs::exists(mrptbridge::truthMapPath(rawlog))) {
    truth_path = mrptbridge::truthMapPath(rawlog);
  }
  if (!truth_path.empty()) truth = io::readRosMap(truth_path);

  const fs::path out_dir(*args.str("--output"));
  fs::create_directories(out_dir);
  if (args.flag("--ply")) fs::create_directories(out_dir / "frames");
  const bool quiet = args.flag("--quiet");

  mrptbridge::RawlogReader reader(rawlog);  // throws naming the file when missing
  const std::size_t total = (!quiet && ::isatty(2)) ? mrptbridge::scanRawlog(rawlog).entries : 0;
  const mrptbridge::UpdObserver observer(config.observer);
  maps::TraversabilityGrid grid(config.grid);
  maps::TraversabilityOcTree tree(config.octree);

  // The annotated rawlog is written as we go, to a temporary file renamed at the end.
  const std::string annotated = (out_dir / "annotated.rawlog").string();
  const std::string annotated_tmp = annotated + ".tmp-" + std::to_string(::getpid());
  std::unique_ptr<mrpt::io::CFileGZOutputStream> annotated_out;
  if (args.flag("--output-rawlog")) {
    annotated_out = std::make_unique<mrpt::io::CFileGZOutputStream>();
    if (!annotated_out->open(annotated_tmp, 1)) throw std::runtime_error("cannot write " + annotated);
  }

  std::map<std::string, std::size_t> skipped;
  std::vector<Eigen::Vector3d> trajectory;
  json timing = {{"convert", 0.0}, {"preprocess", 0.0}, {"normals", 0.0}, {"upd", 0.0},
                 {"classify", 0.0}, {"grid", 0.0}, {"octree", 0.0}, {"frame_total", 0.0}};
  std::vector<double> frame_ms;
  std::size_t read = 0, processed = 0, points_scored = 0;
  Progress progress(!quiet, total);
  const auto run_start = std::chrono::steady_clock::now();

  try {
    mrptbridge::RawlogEntry entry;
    mrptbridge::ObserverResult res;  // reused frame to frame
    while (reader.next(entry)) {
      ++read;
      // Every entry updates the pose tracker, so odometry between selected frames is kept.
      const mrptbridge::RobotPose pose = tracker.update(entry);
      const long idx = static_cast<long>(entry.index);
      if (idx < from || (to >= 0 && idx > to) || (idx - from) % every != 0) {
        ++skipped["outside --from/--to/--every"];
        continue;
      }
      if (!pose.valid()) {
        ++skipped[pose.missing_reason];
        continue;
      }
      const auto frame_start = std::chrono::steady_clock::now();
      observer.observe(*entry.observation, pose.pose_world_robot, res);
      if (!res.ok()) {
        ++skipped[res.skipped_reason];
        continue;
      }
      const auto view = maps::viewPoints(res.points_in_world, res.classes, &res.upd_in_world);
      const double t_s = std::isfinite(entry.timestamp_s) ? entry.timestamp_s : double(idx);
      const Eigen::Vector2d robot_xy = pose.pose_world_robot.translation().head<2>();
      auto t0 = std::chrono::steady_clock::now();
      maps::integrateScan(grid, view, robot_xy, t_s, config.fusion);
      const double grid_ms = msSince(t0);
      t0 = std::chrono::steady_clock::now();
      maps::insertScan(tree, view, res.pose_world_sensor.translation(), config.octree,
                       config.fusion);
      const double octree_ms = msSince(t0);
      const double total_ms = msSince(frame_start);

      const auto& tm = res.timings;
      timing["convert"] = timing["convert"].get<double>() + tm.convert_ms;
      timing["preprocess"] = timing["preprocess"].get<double>() + tm.pipeline.preprocess_ms;
      timing["normals"] = timing["normals"].get<double>() + tm.pipeline.index_ms + tm.pipeline.normals_ms;
      timing["upd"] = timing["upd"].get<double>() + tm.pipeline.upd_ms;
      timing["classify"] = timing["classify"].get<double>() + tm.pipeline.classify_ms;
      timing["grid"] = timing["grid"].get<double>() + grid_ms;
      timing["octree"] = timing["octree"].get<double>() + octree_ms;
      timing["frame_total"] = timing["frame_total"].get<double>() + total_ms;
      frame_ms.push_back(total_ms);
      trajectory.push_back(pose.pose_world_robot.translation());
      points_scored += res.size() - res.upd_in_world.invalid;

      if (args.flag("--ply")) {
        io::ScoredPoints sp;
        const auto& c = res.points_in_world;
        sp.x = c.x, sp.y = c.y, sp.z = c.z;
        sp.nx = res.normals_in_world.nx, sp.ny = res.normals_in_world.ny, sp.nz = res.normals_in_world.nz;
        sp.rx = res.upd_in_world.rx, sp.ry = res.upd_in_world.ry, sp.rz = res.upd_in_world.rz;
        sp.zeta = res.upd_in_world.zeta;
        sp.label = res.classes.label;
        sp.cost = res.classes.cost;
        if (c.hasColor()) sp.r = c.r, sp.g = c.g, sp.b = c.b;
        char name[32];
        std::snprintf(name, sizeof name, "%06ld.ply", idx);
        io::writeScoredPly((out_dir / "frames" / name).string(), sp);
      }
      if (annotated_out) {
        auto arch = mrpt::serialization::archiveFrom(*annotated_out);
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
        const Eigen::Isometry3d robot_world = pose.pose_world_robot.inverse();
        for (std::size_t i = 0; i < res.size(); ++i) {
          if (res.classes.label[i] != Label::NonTraversable) continue;
          const Eigen::Vector3d p = robot_world * res.points_in_world.point(i).cast<double>();
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
      ++processed;
      progress.update(read);
    }
  } catch (...) {
    std::error_code ec;
    if (annotated_out) {
      annotated_out->close();
      fs::remove(annotated_tmp, ec);
    }
    throw;
  }
  progress.finish();
  if (annotated_out) {
    annotated_out->close();
    fs::rename(annotated_tmp, annotated);
  }
  for (const auto& [reason, n] : reader.stats().skipped) skipped[reason] += n;

  // Exports.
  const std::string map = (out_dir / "map").string();
  maps::writeColourPng(grid, map + ".png");
  maps::writeRosMap(grid, map);
  tree.updateInnerOccupancy();
  maps::writeTraversabilityOt(tree, map + ".ot");
  maps::writeOccupancyBt(tree, map + ".bt");
  maps::writeColourOt(tree, map + "_colour.ot");
  write3DScene(grid, trajectory, map + ".3Dscene");

  const maps::GridStats gs = maps::computeStats(grid);
  const maps::OctreeStats os = maps::computeStats(tree);
  json summary;
  summary["rawlog"] = rawlog;
  summary["config"] = *args.str("--config");
  summary["frames_read"] = read;
  summary["frames_processed"] = processed;
  json skipped_json = json::object();
  for (const auto& [reason, n] : skipped) skipped_json[reason] = n;
  summary["frames_skipped"] = skipped_json;
  summary["pose_source"] = mrptbridge::toString(tracker.kind());
  summary["points_scored"] = points_scored;
  const double n = processed ? double(processed) : 1.0;
  json per_frame = json::object();
  for (auto it = timing.begin(); it != timing.end(); ++it) per_frame[it.key()] = it.value().get<double>() / n;
  std::sort(frame_ms.begin(), frame_ms.end());
  per_frame["frame_median"] = frame_ms.empty() ? 0.0 : frame_ms[frame_ms.size() / 2];
  summary["timing_ms_per_frame"] = per_frame;
  summary["wall_time_s"] = msSince(run_start) / 1000.0;
  summary["grid"] = {{"cell_size_m", grid.cellSize()},
                     {"cells", gs.cells},
                     {"known", gs.known},
                     {"traversable", gs.traversable},
                     {"non_traversable", gs.non_traversable},
                     {"memory_bytes", gs.memory_bytes},
                     {"x_min_m", grid.xMin()}, {"y_min_m", grid.yMin()},
                     {"x_max_m", grid.xMax()}, {"y_max_m", grid.yMax()}};
  summary["octree"] = {{"resolution_m", tree.getResolution()},
                       {"leaves", os.leaves},
                       {"occupied_leaves", os.occupied_leaves},
                       {"non_traversable_leaves", os.non_traversable_leaves},
                       {"memory_bytes", os.memory_bytes}};
  if (truth) {
    summary["ground_truth"] = {
        {"map", truth_path},
        {"tolerance_m", config.evaluation.tolerance_m},
        {"scores", scoresJson(scoreAgainstTruth(grid, *truth, config.evaluation.tolerance_m))},
        {"scores_strict", scoresJson(scoreAgainstTruth(grid, *truth, 0.0))}};
  }
  summary["outputs"] = {"map.png", "map.pgm", "map.yaml", "map.ot", "map.bt", "map_colour.ot",
                        "map.3Dscene"};
  io::writeJsonAtomically((out_dir / "summary.json").string(), summary);

  std::printf("%s: %zu frames read, %zu processed (median %.1f ms/frame); map: %zu known cells, "
              "%zu non-traversable -> %s\n",
              rawlog.c_str(), read, processed, per_frame["frame_median"].get<double>(), gs.known,
              gs.non_traversable, out_dir.string().c_str());
  if (truth) {
    const auto& sc = summary["ground_truth"]["scores"];
    std::printf("  against the ground truth (tolerance %.2f m): precision %s, recall %s\n",
                config.evaluation.tolerance_m, sc["precision"].dump().c_str(),
                sc["recall"].dump().c_str());
  }
  return 0;
}

}  // namespace upd::app
