#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "agreement.h"
#include "cases.h"
#include "upd/core/kdtree.h"
#include "upd/core/preprocess.h"
#include "upd/sim/scenes.h"
#include "upd/core/stopwatch.h"
#include "upd/io/cloud_io.h"

namespace core = upd::core;

namespace upd::bench {

using namespace upd::sim;  // generated worlds, scenes and the depth renderer

namespace {

// Our exact path, once, single core like the peer, when its neighbour visits are affordable.
double timeOursExact(const core::PointCloud& cloud, const core::PipelineParams& params, double exact_cost,
                     const Options& o) {
  if (exact_cost >= (o.quick ? 3e8 : 3e9)) return kNaN;
  core::PipelineParams exact = params;
  exact.upd.method = core::UpdMethod::Exact;
  const core::Stopwatch watch;
  const core::PipelineResult er = core::runPipeline(cloud, exact);
  return watch.elapsedMs();
}

// The PCL peer, once, when it takes less than a few minutes; its times into c["pcl"].
double timePclPeer(const core::PointCloud& cloud, const core::PipelineParams& params, double exact_cost,
                   const Options& o, json& c) {
  omp_set_num_threads(1);
  if (o.quick) {
    c["pcl"] = {{"skipped", "--quick"}};
    return kNaN;
  }
  if (exact_cost > 6e9) {
    c["pcl"] = {{"skipped", "estimated " +
                                std::to_string(static_cast<long long>(exact_cost / 1e9)) +
                                "e9 neighbour visits (minutes)"}};
    return kNaN;
  }
  const PeerResult peer = runPclPipeline(cloud, peerOf(params));
  c["pcl"] = {{"total_ms", peer.total_ms},
              {"voxel_ms", peer.voxel_ms},
              {"normals_ms", peer.normals_ms},
              {"upd_ms", peer.upd_ms},
              {"points_scored", peer.cloud.size()}};
  return peer.total_ms;
}

// A case with our fast path, our exact path and the PCL peer at identical settings.
json peerCase(const std::string& name, const std::string& source, const core::PointCloud& cloud,
              const core::PipelineParams& params, const Options& o, int repeats, Report& report,
              bool count_for_speedup_target) {
  json c = {{"name", name},
            {"source", source},
            {"points_in", cloud.size()},
            {"fast_exact_band", params.upd.fast_exact_band}};
  omp_set_num_threads(1);
  core::PipelineParams fast = params;
  fast.upd.method = core::UpdMethod::Fast;
  core::PipelineResult fr;
  const double ours = timeMedian([&] { fr = core::runPipeline(cloud, fast); }, repeats);
  c["points_scored"] = fr.cloud.size();
  c["ours_fast_ms"] = num(ours);
  c["ours_fast_stages"] = {{"preprocess_ms", fr.timings.preprocess_ms},
                           {"normals_ms", fr.timings.normals_ms},
                           {"upd_ms", fr.timings.upd_ms},
                           {"classify_ms", fr.timings.classify_ms}};
  const double exact_cost = peerCostEstimate(cloud, params);
  const double ours_exact = timeOursExact(cloud, params, exact_cost, o);
  c["ours_exact_ms"] = num(ours_exact);
  c["exact_neighbour_visits"] = exact_cost;
  // Agreement with exact on the same pre-processed cloud (two threads: it is not timed).
  omp_set_num_threads(2);
  const ExactReference ref = exactReference(fr.cloud, params, o.quick ? 3000 : 20000);
  const Agreement a = agreement(ref, fr.upd, params);
  c["agreement"] = a.toJson();
  report.target(name + ": mean |dzeta| fast vs exact", a.mean_abs_dzeta, kMaxMeanDzeta, true, "");
  report.target(name + ": same label fast vs exact", a.same_label, kMinSameLabel, false, "");
  const double pcl_ms = timePclPeer(cloud, params, exact_cost, o, c);
  c["ratio_pcl_over_ours"] = num(pcl_ms / ours);
  c["ratio_ours_exact_over_fast"] = num(ours_exact / ours);
  if (count_for_speedup_target && std::isfinite(pcl_ms)) {
    report.target(name + ": PCL pipeline / ours", pcl_ms / ours, kMinSpeedupVsPcl, false, "x");
  }
  std::printf(
      "%-34s %8zu pts  ours %9.2f ms  exact %9.1f ms  PCL %9.1f ms  PCL/ours %7.1fx  "
      "|dz| %.4f  labels %.2f%%%s\n",
      name.c_str(), fr.cloud.size(), ours, ours_exact, pcl_ms, pcl_ms / ours, a.mean_abs_dzeta,
      100 * a.same_label,
      a.compared < a.finite ? (" (" + std::to_string(a.compared) + " sampled)").c_str() : "");
  std::fflush(stdout);
  return c;
}

// The outdoor LiDAR scan: the settings of config/lidar.ini (range 1-40 m, voxel 0.1 m,
// normals 0.5 m, d_m 1.0 m, 6 lattice cells per d_m), identical on both sides.
json lidarCase(const Options& o, Report& report) {
  const auto path = dataFile(o, "fast_gicp/251370668.pcd");
  if (!path) {
    std::printf("lidar fast_gicp: skipped (file not found)\n");
    return {{"name", "lidar fast_gicp d_m 1.0"}, {"skipped", "fast_gicp/251370668.pcd not found"}};
  }
  const core::PointCloud lidar = io::readCloud(*path);
  core::PipelineParams p = pclSettings(Eigen::Vector3f::UnitZ(), 0.1, 0.5, 1.0);
  p.preprocess.range_enabled = true;
  p.preprocess.range_min_m = 1.0;
  p.preprocess.range_max_m = 40.0;
  p.upd.min_neighbors = 3;
  p.upd.fast_cells_per_radius = 6;
  p.classify.zeta_min = 0.93;
  p.classify.zeta_caution = 0.98;
  p.classify.max_slope_rad = 20.0 * core::kDegToRad;
  p.classify.min_neighbors = 5;
  // The peer has no range filter of its own: it gets the cut cloud.
  core::PipelineParams cut = p;
  cut.preprocess.voxel_enabled = false;
  const core::PointCloud in_range = core::preprocess(lidar, cut.preprocess);
  core::PipelineParams rest = p;
  rest.preprocess.range_enabled = false;
  return peerCase("lidar fast_gicp d_m 1.0",
                  "../shared/data/fast_gicp/251370668.pcd "
                  "(range 1-40 m applied first)",
                  in_range, rest, o, o.repeats, report, false);
}

// factor tiles of the rocks tile on a 4-wide grid, 3.05 m apart (the tile is 3 m across): a
// bigger field of rocks at the same density, so the work per point should stay the same.
core::PointCloud rocksField(const Scene& tile, int factor) {
  core::PointCloud field;
  field.reserve(tile.cloud.size() * static_cast<std::size_t>(factor));
  for (int t = 0; t < factor; ++t) {
    const float dx = 3.05f * static_cast<float>(t % 4), dy = 3.05f * static_cast<float>(t / 4);
    for (std::size_t i = 0; i < tile.cloud.size(); ++i) {
      field.push_back(tile.cloud.x[i] + dx, tile.cloud.y[i] + dy, tile.cloud.z[i]);
    }
  }
  field.sensor_origin = tile.cloud.sensor_origin;
  return field;
}

}  // namespace

core::PipelineParams pclSettings(const Eigen::Vector3f& up, double voxel_m, double normal_radius_m,
                           double d_m) {
  core::PipelineParams p;
  p.up = up;
  p.preprocess.disableAll();
  p.preprocess.voxel_enabled = voxel_m > 0;
  p.preprocess.voxel_m = voxel_m > 0 ? voxel_m : 0.02;
  p.normals.radius_m = normal_radius_m;
  p.upd.radius_m = d_m;
  // The points within kExactBand of zeta_min get the exact sums (as config/lidar.ini and
  // config/tractor-stereo.ini): cheap on these clouds, a few dozen points per lattice cell. The
  // sensor-rate frame pipeline leaves it off, as UpdParams does by default.
  p.upd.fast_exact_band = kExactBand;
  return p;
}

PeerSettings peerOf(const core::PipelineParams& p) {
  PeerSettings s;
  s.voxel_enabled = p.preprocess.voxel_enabled;
  s.voxel_m = p.preprocess.voxel_m;
  s.normal_radius_m = p.normals.radius_m;
  s.upd_radius_m = p.upd.radius_m;
  s.min_neighbors = p.upd.min_neighbors;
  s.up = p.unitUp();
  s.vertical_band_rad = p.normals.vertical_band_rad;
  return s;
}

double peerCostEstimate(const core::PointCloud& cloud, const core::PipelineParams& p) {
  const core::PointCloud pre = core::preprocess(cloud, p.preprocess);
  if (pre.empty()) return 0;
  const core::KdTree tree(pre);
  std::vector<std::uint32_t> nb;
  double sum = 0;
  const std::size_t step = std::max<std::size_t>(1, pre.size() / 64);
  std::size_t samples = 0;
  for (std::size_t i = 0; i < pre.size(); i += step) {
    if (!pre.isFinite(i)) continue;
    tree.radiusSearch(pre.point(i), static_cast<float>(p.upd.radius_m), nb);
    sum += static_cast<double>(nb.size());
    ++samples;
  }
  return samples ? sum / static_cast<double>(samples) * static_cast<double>(pre.size()) : 0;
}

json pclSettingsCases(const std::vector<Frame>& frames, const Options& o, Report& report) {
  printRule();
  std::printf(
      "At the PCL peer's settings (one core; PCL run once): ours fast (exact sums within %.2f "
      "of zeta_min), ours exact, PCL pipeline; agreement of fast with exact\n",
      kExactBand);
  printRule();
  json peer_cases = json::array();
  for (const Frame& fr : frames) {
    if (!fr.available) {
      peer_cases.push_back({{"name", fr.name + " (voxel 0.02)"}, {"skipped", fr.skip_reason}});
      continue;
    }
    const core::PointCloud cloud = inputCloud(fr);
    peer_cases.push_back(peerCase(fr.name + " voxel 0.02", fr.source, cloud,
                                  pclSettings(fr.up, 0.02, 0.05, 0.5), o, o.repeats, report, true));
  }
  peer_cases.push_back(lidarCase(o, report));
  // The paper's corner sampled every 0.01 m: no voxel grid, normals 0.05 m, d_m 0.5 m.
  const Scene corner = makeScene("corner");
  peer_cases.push_back(peerCase("corner 0.01 m", "makeScene(\"corner\"), 0.01 m grid",
                                corner.cloud, pclSettings(corner.up, 0, 0.05, 0.5), o, o.repeats,
                                report, false));
  return peer_cases;
}

json growthWithSizeCases(const Options& o, Report& report) {
  printTitle(
      "Growth with the number of points: 1 to 16 tiles of makeScene(\"rocks\") (0.02 m "
      "grid, 3 x 3 m each) side by side, no voxel grid, normals 0.05 m, d_m 0.5 m");
  json size_cases = json::array();
  double per_point_x1 = kNaN, per_point_x16 = kNaN;
  SceneParams tile_params;
  tile_params.spacing_m = 0.02;
  tile_params.noise_m = 0.002;
  const Scene tile = makeScene("rocks", tile_params);
  for (const int factor : {1, 2, 4, 8, 16}) {
    const core::PointCloud field = rocksField(tile, factor);
    const int reps = std::max(3, o.repeats / factor);
    json c = peerCase("rocks x" + std::to_string(factor),
                      std::to_string(factor) + " tiles of makeScene(\"rocks\"), 0.02 m grid", field,
                      pclSettings(tile.up, 0, 0.05, 0.5), o, reps, report, false);
    const double per_point = c["ours_fast_ms"].get<double>() / static_cast<double>(field.size());
    c["ours_ns_per_point"] = per_point * 1e6;
    if (factor == 1) per_point_x1 = per_point;
    if (factor == 16) per_point_x16 = per_point;
    size_cases.push_back(c);
  }
  report.target("time per point, x16 / x1 (linear growth)", per_point_x16 / per_point_x1,
                kMaxPerPointGrowth, true, "x");
  return size_cases;
}

}  // namespace upd::bench
