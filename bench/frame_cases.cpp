#include <omp.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "agreement.h"
#include "cases.h"
#include "upd/core/fast_normals.h"

namespace core = upd::core;

namespace upd::bench {
namespace {

json frameTimingCase(const Frame& fr, const Options& o, Report& report, core::PipelineResult& result) {
  json c = {{"name", fr.name}, {"source", fr.source}};
  if (!fr.available) {
    c["skipped"] = fr.skip_reason;
    std::printf("%-30s skipped: %s\n", fr.name.c_str(), fr.skip_reason.c_str());
    return c;
  }
  const core::PipelineParams p = frameParams(fr, 0.5);
  CoreProbe probe;
  const auto [t1, t2] = timeOneAndTwoCores(fr, p, o.repeats, &result, &probe);
  c["points"] = t1.points;
  c["points_scored"] = t1.scored;
  c["starts_from"] = fr.depth ? "depth image" : "organized cloud";
  c["one_core_ms"] = num(t1.total_ms);
  c["one_core_stages"] = t1.stages;
  c["two_core_ms"] = num(t2.total_ms);
  c["two_core_stages"] = t2.stages;
  c["two_core_speedup"] = num(t1.total_ms / t2.total_ms);
  probe.addTo(c);
  c["normals_method"] = result.organized_normals ? "image-window scans" : "hash grid";
  // UpdParams::fast_cells_per_point: the lattice's cells per d_m on this frame.
  c["lattice_cells_per_radius"] = result.fast_cells_per_radius;
  report.target(fr.name + ": frame pipeline, one core (median)", t1.total_ms, kFrameBudgetMs,
                true, "ms");
  report.target(fr.name + ": second core speedup", t1.total_ms / t2.total_ms, kMinTwoCoreSpeedup,
                false, "x", machineNote(probe));
  std::printf(
      "%-30s %7zu px %7zu scored  one core %7.2f ms  two cores %7.2f ms (x%.2f; machine x%.2f, "
      "%.0f ns)  "
      "[normals %.2f, UPD %.2f, labels %.2f, map %.2f ms]\n",
      fr.name.c_str(), t1.points, t1.scored, t1.total_ms, t2.total_ms, t1.total_ms / t2.total_ms,
      probe.speedup(), probe.roundTripNs(), t1.stages["normals_ms"].get<double>(),
      t1.stages["upd_ms"].get<double>(),
      t1.stages["classify_ms"].get<double>(), t1.stages["map_update_ms"].get<double>());
  std::fflush(stdout);
  return c;
}

// What the labels' agreement costs at full resolution (not a target: the trade-off
// docs/PERFORMANCE.md discusses): normals per 3 x 3 pixels and exact sums within 0.004 of
// zeta_min.
json accuracySettingsCase(const Frame& frame, const core::PipelineParams& p, const ExactReference& ref,
                          const Options& o) {
  core::PipelineParams accurate = p;
  accurate.normals.fast_block_px = 3;
  accurate.upd.fast_exact_band = 0.004;
  omp_set_num_threads(1);
  core::PipelineResult ar;
  const FrameTiming at = timeFramePipeline(frame, accurate, std::max(3, o.repeats / 3), &ar);
  omp_set_num_threads(2);
  const Agreement aa = agreement(ref, ar.upd, accurate);
  std::printf(
      "%-30s   with 3 x 3 px normals and exact sums within 0.004 of zeta_min: one core "
      "%.2f ms, mean |dzeta| %.5f, same label %.3f%%\n",
      "", at.total_ms, aa.mean_abs_dzeta, 100 * aa.same_label);
  std::fflush(stdout);
  return {{"fast_block_px", 3},
          {"fast_exact_band", 0.004},
          {"one_core_ms", num(at.total_ms)},
          {"agreement", aa.toJson()}};
}

json radiusCase(const Frame& gen, double dm, const Options& o, Report& report, double& total_ms) {
  const core::PipelineParams p = frameParams(gen, dm);
  omp_set_num_threads(1);
  core::PipelineResult r;
  const FrameTiming t = timeFramePipeline(gen, p, o.repeats, &r);
  total_ms = t.total_ms;
  omp_set_num_threads(2);
  const ExactReference ref = exactReference(r.cloud, p, o.quick ? 1000 : (dm > 1 ? 3000 : 6000));
  const Agreement a = agreement(ref, r.upd, p);
  json c = {
      {"d_m", dm}, {"one_core_ms", num(t.total_ms)}, {"stages", t.stages}, {"agreement", a.toJson()}};
  // The peer at its settings on this frame, when it takes less than a few minutes.
  const core::PipelineParams ps = pclSettings(gen.up, 0.02, 0.05, dm);
  const double cost = peerCostEstimate(r.cloud, ps);
  double pcl_ms = kNaN;
  if (o.quick) {
    c["pcl"] = {{"skipped", "--quick"}};
  } else if (cost > 6e9) {
    c["pcl"] = {{"skipped", "estimated neighbour visits " + std::to_string(cost)}};
  } else {
    omp_set_num_threads(1);
    pcl_ms = runPclPipeline(r.cloud, peerOf(ps)).total_ms;
    c["pcl"] = {{"total_ms", pcl_ms}, {"settings", "voxel 0.02, normals 0.05"}};
  }
  c["ratio_pcl_over_ours"] = num(pcl_ms / t.total_ms);
  const std::string dm_name = "generated frame d_m " + std::to_string(dm).substr(0, 4);
  report.target(dm_name + ": mean |dzeta| fast vs exact", a.mean_abs_dzeta, kMaxMeanDzeta, true,
                "");
  report.target(dm_name + ": same label fast vs exact", a.same_label, kMinSameLabel, false, "");
  std::printf(
      "d_m %.2f m: one core %7.2f ms [UPD %.2f ms]  PCL %9.1f ms  PCL/ours %7.1fx  "
      "|dz| %.4f  labels %.2f%% (%zu sampled)\n",
      dm, t.total_ms, t.stages["upd_ms"].get<double>(), pcl_ms, pcl_ms / t.total_ms,
      a.mean_abs_dzeta, 100 * a.same_label, a.compared);
  std::fflush(stdout);
  return c;
}

}  // namespace

core::PipelineParams frameParams(const Frame& f, double d_m) {
  core::PipelineParams p;
  p.up = f.up;
  p.preprocess.disableAll();  // keep the image: every pixel is scored
  p.normals.radius_m = 0.05;
  p.upd.radius_m = d_m;
  return p;
}

json frameTimingCases(const std::vector<Frame>& frames, const Options& o, Report& report,
                      std::vector<core::PipelineResult>& results) {
  printRule();
  std::printf(
      "Frame pipeline, organized 640 x 480, every pixel scored: depth image / organized "
      "cloud -> normals (0.05 m) -> UPD (d_m 0.5 m) -> labels -> map update\n");
  std::printf("map update: %s\n", mapStageKind());
  printRule();
  json frame_cases = json::array();
  results.assign(frames.size(), core::PipelineResult());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    frame_cases.push_back(frameTimingCase(frames[f], o, report, results[f]));
  }
  const double peak_mb = peakRssMb();
  report.root["frame_pipeline_peak_rss_mb"] = peak_mb;
  report.target("peak memory after the 640 x 480 frame pipelines (whole process)", peak_mb,
                kMaxPeakMemoryMb, true, "MB");
  std::printf("peak resident memory so far (the frames loaded and scored): %.0f MB\n", peak_mb);
  return frame_cases;
}

void frameAgreementCases(const std::vector<Frame>& frames,
                         const std::vector<core::PipelineResult>& results, const Options& o,
                         Report& report, json& frame_cases) {
  printTitle(
      "Agreement of the frame pipeline with the exact path (same cloud, full "
      "resolution; exact UPD on evenly spaced samples)");
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (!frames[f].available) continue;
    const core::PipelineParams p = frameParams(frames[f], 0.5);
    omp_set_num_threads(2);
    const ExactReference ref = exactReference(results[f].cloud, p, o.quick ? 2000 : 12000);
    const Agreement a = agreement(ref, results[f].upd, p);
    frame_cases[f]["agreement"] = a.toJson();
    report.target(frames[f].name + ": frame mean |dzeta| fast vs exact", a.mean_abs_dzeta,
                  kMaxMeanDzeta, true, "");
    report.target(frames[f].name + ": frame same label fast vs exact", a.same_label, kMinSameLabel,
                  false, "");
    std::printf(
        "%-30s %6zu of %6zu points compared: mean |dzeta| %.5f, max %.4f, same label "
        "%.3f%% (%d lattice cells per d_m; exact normals %.0f ms, exact UPD of the sample %.0f "
        "ms, 2 threads)\n",
        frames[f].name.c_str(), a.compared, a.finite, a.mean_abs_dzeta, a.max_abs_dzeta,
        100 * a.same_label, results[f].fast_cells_per_radius, a.exact_normals_ms, a.exact_upd_ms);
    frame_cases[f]["accuracy_settings"] = accuracySettingsCase(frames[f], p, ref, o);
  }
}

json normalsAloneCases(const std::vector<Frame>& frames, const Options& o) {
  printTitle(
      "Normals alone, organized frames, one core: computeNormalsOrganized (r = 0.05 m) "
      "vs PCL IntegralImageNormalEstimation (COVARIANCE_MATRIX, smoothing 10 px)");
  json normal_cases = json::array();
  for (const Frame& fr : frames) {
    if (!fr.available) continue;
    omp_set_num_threads(1);
    core::NormalParams np;
    np.radius_m = 0.05;
    std::size_t valid = 0;
    const double ours = timeMedian(
        [&] { valid = fr.cloud.size() - core::computeNormalsOrganized(fr.cloud, np, fr.up).invalid; },
        o.repeats);
    std::vector<double> pcl_runs;
    std::size_t pcl_valid = 0;
    for (int r = 0; r < std::max(3, o.repeats / 3); ++r) {
      const IntegralPeerResult pr = runPclIntegralNormals(fr.cloud, 0.02f, 10.0f);
      pcl_runs.push_back(pr.ms);
      pcl_valid = pr.valid;
    }
    const double pcl = median(pcl_runs);
    normal_cases.push_back({{"name", fr.name},
                            {"ours_ms", num(ours)},
                            {"ours_valid", valid},
                            {"pcl_integral_ms", num(pcl)},
                            {"pcl_valid", pcl_valid},
                            {"ratio_pcl_over_ours", num(pcl / ours)}});
    std::printf("%-30s ours %7.2f ms (%zu normals)  PCL %7.2f ms (%zu normals)  PCL/ours %.1fx\n",
                fr.name.c_str(), ours, valid, pcl, pcl_valid, pcl / ours);
    std::fflush(stdout);
  }
  return normal_cases;
}

json growthWithRadiusCases(const Frame& generated, const Options& o, Report& report) {
  printTitle("Growth with d_m: the generated Kinect frame, frame pipeline on one core");
  json dm_cases = json::array();
  double t_small = kNaN, t_large = kNaN;
  for (const double dm : {0.25, 0.5, 1.0, 2.0}) {
    double total_ms = kNaN;
    dm_cases.push_back(radiusCase(generated, dm, o, report, total_ms));
    if (dm == 0.25) t_small = total_ms;
    if (dm == 2.0) t_large = total_ms;
  }
  report.target("time at d_m 2 m / time at d_m 0.25 m", t_large / t_small, kMaxDmRatio, true, "x");
  return dm_cases;
}

}  // namespace upd::bench
