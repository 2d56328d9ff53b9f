// `upd baseline`: the paper's baselines (roughness index, inclination index) on one cloud, beside
// the UPD, as a scored PLY that `upd render --color label|cost` draws and a JSON summary: what
// the paper's Fig. 5 compares.
#include "cli.h"
#include "commands.h"

#include "upd/core/baselines.h"
#include "upd/core/pipeline.h"
#include "upd/io/cloud_io.h"
#include "upd/io/json_io.h"
#include "run_config.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace upd::app {

const char* const kBaselineUsage =
    "usage: upd baseline INPUT --output OUT.ply [options]\n"
    "  Pre-processes INPUT as `upd analyze` does and scores it with the roughness index (the\n"
    "  standard deviation of elevation over the d_m ball; non-traversable above\n"
    "  [BaselineParams] roughness_max_m) and the inclination index, over the UPD's d_m.\n"
    "  OUT.ply is a scored PLY whose label is the roughness index's rule and whose cost is\n"
    "  roughness / roughness_max_m (1 at the threshold, not clamped), so `upd render OUT.ply\n"
    "  --color label` draws it like the UPD's labels; zeta is the UPD's.\n\n"
    "options:\n"
    "  --output OUT.ply      the scored PLY (required)\n"
    "  --radius-m D          d_m [m] of both indices and the UPD (default 0.5)\n"
    "  --up X,Y,Z            gravity-up in the cloud frame (default 0,0,1)\n"
    "  --no-preprocess       score the input as it is\n"
    "  --config FILE.ini     parameters ([BaselineParams], the pipeline's sections)\n"
    "  --stats-json OUT.json counts of both rules and the UPD's, and roughness statistics\n";

namespace {

nlohmann::json labelCounts(const std::vector<core::Label>& labels) {
  std::size_t n[3] = {0, 0, 0};
  for (core::Label l : labels) ++n[std::min<int>(2, static_cast<int>(l))];
  return {{"traversable", n[0]}, {"non_traversable", n[1]}, {"unknown", n[2]}};
}

nlohmann::json finiteStats(std::vector<float> v, double scale) {
  v.erase(std::remove_if(v.begin(), v.end(), [](float x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return nullptr;
  std::sort(v.begin(), v.end());
  auto at = [&](double q) { return scale * v[std::size_t(q * double(v.size() - 1))]; };
  return {{"min", at(0)}, {"median", at(0.5)}, {"p95", at(0.95)}, {"max", at(1)}};
}

}  // namespace

int runBaseline(const std::vector<std::string>& argv) {
  const Args args(argv, {"--output", "--radius-m", "--up", "--config", "--stats-json"},
                  {"--no-preprocess"});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one INPUT file");
  const auto output = args.str("--output");
  if (!output) throw UsageError("--output OUT.ply is required");
  RunConfig cfg;
  if (const auto f = args.str("--config")) cfg = loadRunConfig(*f);
  core::PipelineParams& params = cfg.observer.pipeline;
  if (const auto v = args.number("--radius-m")) params.upd.radius_m = *v;
  if (const auto v = args.vector3("--up")) params.up = *v;
  if (args.flag("--no-preprocess")) params.preprocess.disableAll();
  cfg.baseline.radius_m = params.upd.radius_m;
  params.validate();
  cfg.baseline.validate();

  const core::PointCloud cloud = io::readCloud(args.positionals()[0]);
  const core::PipelineResult res = core::runPipeline(cloud, params);
  const core::KdTree tree(res.cloud);
  const core::BaselineResult base =
      core::computeBaselines(res.cloud, tree, params.up.normalized(), cfg.baseline);

  io::ScoredPoints pts = io::scoredPointsOf(res);
  std::vector<float> cost(base.roughness_m.size());
  for (std::size_t i = 0; i < cost.size(); ++i)
    cost[i] = base.roughness_m[i] / float(cfg.baseline.roughness_max_m);
  pts.label = base.roughness_label;
  pts.cost = cost;
  io::writeScoredPly(*output, pts);
  if (const auto out = args.str("--stats-json")) {
    io::writeJsonAtomically(
        *out, {{"points", res.cloud.size()},
               {"radius_m", params.upd.radius_m},
               {"roughness_max_m", cfg.baseline.roughness_max_m},
               {"roughness", labelCounts(base.roughness_label)},
               {"roughness_m", finiteStats(base.roughness_m, 1.0)},
               {"inclination_deg", finiteStats(base.inclination_rad, 180.0 / M_PI)},
               {"upd", labelCounts(res.classes.label)}});
  }
  std::printf("%s: %zu points, roughness index (d_m = %.3g m) -> %s\n",
              args.positionals()[0].c_str(), res.cloud.size(), params.upd.radius_m,
              output->c_str());
  return 0;
}

}  // namespace upd::app
