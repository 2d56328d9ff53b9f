// The paper's whole pipeline on both sides, and the sensor-rate path beside PCL's integral-image
// normals: the two comparisons of the pipelines as `upd` runs them (config/dune-kinect.ini and
// config/dune-kinect-realtime.ini), each as a ratio measured in the same run.
#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "agreement.h"
#include "cases.h"
#include "upd/core/preprocess.h"
#include "upd/core/stopwatch.h"

namespace core = upd::core;

namespace upd::bench {
namespace {

// The runs' stage times and their medians.
struct StageMedians {
  std::vector<double> pre, nrm, upd, cls;
  void add(const core::StageTimings& s) {
    pre.push_back(s.preprocess_ms), nrm.push_back(s.normals_ms);
    upd.push_back(s.upd_ms), cls.push_back(s.classify_ms);
  }
  json toJson() const {
    return {{"preprocess_ms", median(pre)},
            {"normals_ms", median(nrm)},
            {"upd_ms", median(upd)},
            {"classify_ms", median(cls)}};
  }
};

// One core and two in turn, a block of runs at a time (oneAndTwoCoresInBlocks), on the paper's
// pipeline (our buffers kept from run to run); the stage medians of each into stages and
// two_stages.
struct PaperTiming {
  double one_ms = kNaN, two_ms = kNaN;
  CoreProbe probe;  // sampled before each pair of blocks
  json stages, two_stages;
  std::size_t scored = 0;
};

PaperTiming timePaperPipeline(const core::PointCloud& cloud, const core::PipelineParams& p,
                              int repeats) {
  core::PipelineResult one, two;
  std::vector<double> t1, t2;
  StageMedians s1, s2;
  PaperTiming t;
  // (Each side's frame timed with its own result, kept from frame to frame.)
  const auto frame = [&](core::PipelineResult& r, std::vector<double>& ms, StageMedians& s,
                         bool record) {
    const core::Stopwatch w;
    core::runPipeline(cloud, p, r);
    if (!record) return;
    ms.push_back(w.elapsedMs());
    s.add(r.timings);
  };
  oneAndTwoCoresInBlocks(
      repeats, &t.probe, [&](bool record) { frame(one, t1, s1, record); },
      [&](bool record) { frame(two, t2, s2, record); });
  t.one_ms = median(t1), t.two_ms = median(t2);
  t.stages = s1.toJson(), t.two_stages = s2.toJson();
  t.scored = one.cloud.size();
  return t;
}

// The PCL side: the same cut-off (applied before its clock starts: PCL has no range filter of
// its own), then VoxelGrid, StatisticalOutlierRemoval, NormalEstimation and the UPD by a radius
// search, one core.
json pclPaperPipeline(const core::PointCloud& cloud, const core::PipelineParams& p,
                      double& total_ms) {
  core::PreprocessParams cut = p.preprocess;
  cut.voxel_enabled = cut.outlier_enabled = false;
  const core::PointCloud in_range = core::preprocess(cloud, cut);
  PeerSettings s = peerOf(p);
  s.outlier_enabled = p.preprocess.outlier_enabled;
  s.outlier_k = p.preprocess.outlier_k;
  s.outlier_std_mul = p.preprocess.outlier_std_mul;
  omp_set_num_threads(1);
  const PeerResult r = runPclPipeline(in_range, s);
  total_ms = r.total_ms;
  return {{"total_ms", r.total_ms},  {"voxel_ms", r.voxel_ms}, {"outlier_ms", r.outlier_ms},
          {"normals_ms", r.normals_ms}, {"upd_ms", r.upd_ms},    {"points_scored", r.cloud.size()}};
}

json paperCase(const Frame& fr, const Options& o, Report& report) {
  json c = {{"name", fr.name}, {"source", fr.source}};
  if (!fr.available) {
    c["skipped"] = fr.skip_reason;
    std::printf("%-30s skipped: %s\n", fr.name.c_str(), fr.skip_reason.c_str());
    return c;
  }
  const core::PointCloud cloud = inputCloud(fr);
  const core::PipelineParams p = paperParams(fr.up);
  const PaperTiming t = timePaperPipeline(cloud, p, o.repeats);
  const double pre = t.stages["preprocess_ms"].get<double>();
  c["points_in"] = cloud.size();
  c["points_scored"] = t.scored;
  c["one_core_ms"] = num(t.one_ms);
  c["one_core_stages"] = t.stages;
  c["two_core_ms"] = num(t.two_ms);
  c["two_core_stages"] = t.two_stages;
  c["two_core_speedup"] = num(t.one_ms / t.two_ms);
  t.probe.addTo(c);
  c["preprocess_share"] = num(pre / t.one_ms);
  double pcl_ms = kNaN;
  if (o.quick) {
    c["pcl"] = {{"skipped", "--quick"}};
  } else {
    c["pcl"] = pclPaperPipeline(cloud, p, pcl_ms);
  }
  c["ratio_pcl_over_ours"] = num(pcl_ms / t.one_ms);
  report.target(fr.name + ": paper pipeline, PCL / ours", pcl_ms / t.one_ms, kMinPaperSpeedupVsPcl,
                false, "x");
  report.target(fr.name + ": paper pipeline, pre-processing share", pre / t.one_ms,
                kMaxPreprocessShare, true, "");
  report.target(fr.name + ": paper pipeline, second core", t.one_ms / t.two_ms,
                kMinPipelineTwoCoreSpeedup, false, "x", machineNote(t.probe));
  std::printf(
      "%-30s %7zu scored  ours %7.2f ms [pre %.2f, normals %.2f, UPD %.2f]  two cores %6.2f ms "
      "(x%.2f; machine x%.2f, %.0f ns)  PCL %8.1f ms",
      fr.name.c_str(), t.scored, t.one_ms, pre, t.stages["normals_ms"].get<double>(),
      t.stages["upd_ms"].get<double>(), t.two_ms, t.one_ms / t.two_ms,
      t.probe.speedup(), t.probe.roundTripNs(), pcl_ms);
  if (std::isfinite(pcl_ms)) {
    const json& q = c["pcl"];
    std::printf(" [voxel %.1f, SOR %.1f, normals %.1f, UPD %.1f]  PCL/ours %.0fx",
                q["voxel_ms"].get<double>(), q["outlier_ms"].get<double>(),
                q["normals_ms"].get<double>(), q["upd_ms"].get<double>(), pcl_ms / t.one_ms);
  }
  std::printf("\n");
  std::fflush(stdout);
  return c;
}

// The sensor-rate path on one frame against PCL's integral-image normals alone (its median over
// a few runs, one core), with its agreement with the exact path.
json sensorRateCase(const Frame& fr, const Options& o, Report& report) {
  json c = {{"name", fr.name}, {"source", fr.source}};
  if (!fr.available) {
    c["skipped"] = fr.skip_reason;
    return c;
  }
  const core::PipelineParams p = sensorRateParams(fr.up);
  core::PipelineResult result;
  CoreProbe probe;
  const auto [t1, t2] = timeOneAndTwoCores(fr, p, o.repeats, &result, &probe);
  std::vector<double> pcl_runs;
  omp_set_num_threads(1);
  for (int r = 0; r < std::max(3, o.repeats / 3); ++r) {
    pcl_runs.push_back(runPclIntegralNormals(fr.cloud, 0.02f, 10.0f).ms);
  }
  const double pcl = median(pcl_runs);
  omp_set_num_threads(2);
  const ExactReference ref = exactReference(result.cloud, p, o.quick ? 1000 : 4000);
  const Agreement a = agreement(ref, result.upd, p);
  c["one_core_ms"] = num(t1.total_ms);
  c["one_core_stages"] = t1.stages;
  c["two_core_ms"] = num(t2.total_ms);
  c["two_core_stages"] = t2.stages;
  c["two_core_speedup"] = num(t1.total_ms / t2.total_ms);
  probe.addTo(c);
  c["pcl_integral_normals_ms"] = num(pcl);
  c["ratio_ours_over_pcl_integral"] = num(t1.total_ms / pcl);
  c["agreement"] = a.toJson();
  const std::string n = fr.name + ": sensor-rate path";
  report.target(n + " / PCL integral-image normals", t1.total_ms / pcl, kMaxSensorRateOverIntegral,
                true, "x");
  report.target(n + ", second core", t1.total_ms / t2.total_ms, kMinPipelineTwoCoreSpeedup, false,
                "x", machineNote(probe));
  report.target(n + ", mean |dzeta| vs exact", a.mean_abs_dzeta, kMaxMeanDzeta, true, "");
  report.target(n + ", same label vs exact", a.same_label, kMinSameLabel, false, "");
  std::printf(
      "%-30s ours %6.2f ms [normals %.2f, UPD %.2f, labels %.2f, map %.2f]  two cores %6.2f ms "
      "(x%.2f; machine x%.2f, %.0f ns)  PCL integral normals %6.2f ms  ours/PCL %.2fx  "
      "|dz| %.4f  "
      "labels %.2f%%\n",
      fr.name.c_str(), t1.total_ms, t1.stages["normals_ms"].get<double>(),
      t1.stages["upd_ms"].get<double>(), t1.stages["classify_ms"].get<double>(),
      t1.stages["map_update_ms"].get<double>(), t2.total_ms, t1.total_ms / t2.total_ms,
      probe.speedup(), probe.roundTripNs(), pcl,
      t1.total_ms / pcl, a.mean_abs_dzeta, 100 * a.same_label);
  std::fflush(stdout);
  return c;
}

}  // namespace

core::PipelineParams paperParams(const Eigen::Vector3f& up) {
  core::PipelineParams p;
  p.up = up;
  p.preprocess.range_enabled = true;
  p.preprocess.range_min_m = 0.4;
  p.preprocess.range_max_m = 5.0;
  p.preprocess.voxel_enabled = true;
  p.preprocess.voxel_m = 0.02;
  p.preprocess.outlier_enabled = true;
  p.preprocess.outlier_k = 16;
  p.preprocess.outlier_std_mul = 2.0;
  p.normals.radius_m = 0.05;
  p.upd.radius_m = 0.5;
  return p;
}

core::PipelineParams sensorRateParams(const Eigen::Vector3f& up) {
  core::PipelineParams p;
  p.up = up;
  p.preprocess.disableAll();
  p.preprocess.range_enabled = true;
  p.preprocess.range_min_m = 0.4;
  p.preprocess.range_max_m = 5.0;
  p.normals.radius_m = 0.1;
  p.normals.fast_scan_px = 40;
  p.upd.radius_m = 0.5;
  p.upd.fast_cells_per_radius = 5;
  p.upd.fast_cells_per_point = 0.007;
  p.classify.zeta_min = 0.95;
  p.classify.zeta_caution = 0.99;
  p.classify.max_slope_rad = 25.0 * core::kDegToRad;
  p.classify.min_neighbors = 10;
  return p;
}

namespace {
// A table: its title, then one case per frame.
template <class Case>
json frameTable(const char* title, const std::vector<Frame>& frames, Case&& one_case) {
  printTitle(title);
  json cases = json::array();
  for (const Frame& fr : frames) cases.push_back(one_case(fr));
  return cases;
}
}  // namespace

json paperPipelineCases(const std::vector<Frame>& frames, const Options& o, Report& report) {
  return frameTable(
      "The paper's pipeline (config/dune-kinect.ini's steps): cut-off 0.4-5 m -> voxel 0.02 m -> "
      "outlier filter k 16, 2 sigma -> normals 0.05 m -> UPD d_m 0.5 m; ours one core and two, "
      "PCL one core (VoxelGrid, StatisticalOutlierRemoval, NormalEstimation, UPD by radius "
      "search; the cut-off before its clock)",
      frames, [&](const Frame& fr) { return paperCase(fr, o, report); });
}

json sensorRateCases(const std::vector<Frame>& frames, const Options& o, Report& report) {
  return frameTable(
      "The sensor-rate path (config/dune-kinect-realtime.ini's settings: cut-off 0.4-5 m, "
      "normals 0.1 m, UPD d_m 0.5 m, labels, map update) against PCL's "
      "IntegralImageNormalEstimation alone (COVARIANCE_MATRIX, smoothing 10 px), one core",
      frames, [&](const Frame& fr) { return sensorRateCase(fr, o, report); });
}

}  // namespace upd::bench
