// `upd analyze`: one point cloud file in, per-point UPD, labels and a JSON summary out.
#include "cli.h"
#include "commands.h"

#include "upd/core/pipeline.h"
#include "upd/io/cloud_io.h"
#include "upd/io/json_io.h"
#include "depth_input.h"
#include "run_config.h"

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <limits>

namespace upd::app {

const char* const kAnalyzeUsage =
    "usage: upd analyze INPUT [options]\n"
    "  Scores every point of INPUT (.pcd, .ply, .xyz, a KITTI .bin scan: float32 x y z\n"
    "  intensity per point, or a 16-bit depth .png with --intrinsics) with the Unevenness\n"
    "  Point Descriptor.\n\n"
    "options:\n"
    "  --intrinsics F.yaml   calibration of a depth PNG (OpenCV/RTAB-Map or ROS camera_info\n"
    "                        YAML); its local_transform, when present, moves the cloud to the\n"
    "                        robot frame (up +z), else the cloud stays in the camera-optical\n"
    "                        frame (up 0,-1,0: a level camera)\n"
    "  --depth-scale S       metres per unit of a depth PNG (default 0.001: millimetres)\n"
    "  --mount MOUNT.ini     INPUT is in the camera-optical frame: move it to the robot frame\n"
    "                        (up +z) by this [CameraMountParams] (upd calibrate-mount --output)\n"
    "  --radius-m D          UPD search radius d_m [m] (default 0.5; 1.0 for a tractor)\n"
    "  --normal-radius-m R   PCA normal radius [m] (default 0.1)\n"
    "  --knn K               use the K nearest points (normals and UPD) instead of radii\n"
    "  --voxel-m V           voxel size for down-sampling [m] (default 0.02)\n"
    "  --no-preprocess       no range cut-off, outlier removal or down-sampling\n"
    "  --up X,Y,Z            gravity-up in the cloud frame (default 0,0,1;\n"
    "                        0,-1,0 for a level camera in the optical frame)\n"
    "  --config FILE.ini     parameters from an ini file (see config/*.ini, docs/PARAMETERS.md);\n"
    "                        options given on the command line override it\n"
    "  --output OUT.ply      scored cloud, valid (finite) points only: x y z nx ny nz scalar_rx\n"
    "                        scalar_ry scalar_rz scalar_zeta scalar_label scalar_cost quality\n"
    "                        (= zeta), the names CloudCompare and MeshLab load as fields\n"
    "  --organized           write every point of the scored cloud, invalid (NaN) ones included,\n"
    "                        in cloud order, with its width and height as header comments (an\n"
    "                        organized input keeps them with --no-preprocess)\n"
    "  --stats-json OUT.json summary: counts, zeta statistics, labels, per-stage timings and\n"
    "                        the method used (fast or exact path)\n";

namespace {

// Where the range cut-off removed every finite point (a georeferenced or airborne cloud, far
// from its sensor origin), one line says how far the points lie, so that the fix is at hand.
void noteRangeCutAll(const core::PointCloud& cloud, const core::PreprocessParams& p,
                     const core::PreprocessStats& s) {
  if (!p.range_enabled || s.range_removed == 0 || s.range_removed + s.non_finite < s.points_in) {
    return;
  }
  double lo = std::numeric_limits<double>::infinity(), hi = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.isFinite(i)) continue;
    const double d = (cloud.point(i) - cloud.sensor_origin).cast<double>().norm();
    lo = std::min(lo, d), hi = std::max(hi, d);
  }
  const Eigen::Vector3f& o = cloud.sensor_origin;
  std::fprintf(stderr,
               "upd analyze: note: the range cut-off (%.3g-%.3g m from the sensor origin %g,%g,%g) "
               "removed every point: they lie %.4g-%.4g m from it; set [Preprocess] range_max_m "
               "or range_enabled = false, or --no-preprocess\n",
               p.range_min_m, p.range_max_m, o.x(), o.y(), o.z(), lo, hi);
}

}  // namespace

int runAnalyze(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--radius-m", "--normal-radius-m", "--knn", "--voxel-m", "--up", "--config",
                   "--output", "--stats-json", "--intrinsics", "--depth-scale", "--mount"},
                  {"--no-preprocess", "--organized"});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one INPUT file");
  const std::string input = args.positionals()[0];

  core::PipelineParams params;
  if (const auto cfg = args.str("--config")) params = loadRunConfig(*cfg).observer.pipeline;
  if (const auto v = args.number("--radius-m")) params.upd.radius_m = *v;
  if (const auto v = args.number("--normal-radius-m")) params.normals.radius_m = *v;
  if (const auto v = args.integer("--knn")) params.normals.knn = params.upd.knn = *v;
  if (const auto v = args.number("--voxel-m")) {
    params.preprocess.voxel_enabled = true;
    params.preprocess.voxel_m = *v;
  }
  if (args.flag("--no-preprocess")) params.preprocess.disableAll();
  if (const auto v = args.vector3("--up")) params.up = *v;
  params.validate();  // before reading a possibly large file

  const AnalyzeInput in = readAnalyzeInput(input, args.str("--intrinsics"),
                                          args.number("--depth-scale").value_or(0.001),
                                          args.str("--mount"));
  if (in.up && !args.has("--up")) params.up = *in.up;
  const core::PointCloud& cloud = in.cloud;
  const core::PipelineResult result = core::runPipeline(cloud, params);
  const auto summary = io::summaryJson(result, params, cloud.size());

  if (const auto out = args.str("--output")) {
    io::ScoredPlyOptions ply;
    ply.organized = args.flag("--organized");
    io::writeScoredPly(*out, result, ply);
  }
  if (const auto out = args.str("--stats-json")) io::writeJsonAtomically(*out, summary);

  const auto& c = result.classes;
  std::printf(
      "%s: %zu points in, %zu scored (d_m = %.3g m): %zu traversable, %zu non-traversable, "
      "%zu unknown; %.1f ms\n",
      input.c_str(), cloud.size(), result.cloud.size() - result.upd.invalid,
      params.upd.radius_m, c.traversable, c.non_traversable, c.unknown, result.timings.total_ms);
  // A camera's cloud (optical frame: y down) read with the default up has its floor as a wall:
  // nothing traversable. Said where the user chose no up, so that the fix is one option away.
  if (c.traversable == 0 && c.non_traversable > 0 && !args.has("--up") && !args.has("--config") &&
      !in.up) {
    std::fprintf(stderr,
                 "upd analyze: note: no point is traversable with up = 0,0,1 (the default); a "
                 "cloud in a camera's optical frame (y down) needs --up 0,-1,0 or --mount "
                 "MOUNT.ini\n");
  }
  noteRangeCutAll(cloud, params.preprocess, result.preprocess_stats);
  return 0;
}

}  // namespace upd::app
