// `upd bench-nav`: the navigation benchmark (upd/nav/bench.h). The closed loop of `upd
// navigate` on N generated worlds (seeds S .. S + N - 1), scored against the optimal path on the
// ground truth; one progress line per world, worlds.csv and summary.json rewritten after every
// world, the path pictures of each failure, and optionally a check against expected rows.
#include "cli.h"
#include "commands.h"
#include "nav_run_config.h"
#include "output_folder.h"

#include "upd/io/json_io.h"
#include "upd/nav/bench.h"
#include "upd/nav/nav_config.h"

#include <cstdio>
#include <filesystem>
#include <string>

namespace upd::app {

const char* const kBenchNavUsage =
    "usage: upd bench-nav --worlds N --output DIR [--seed S] [--difficulty D]\n"
    "                     [--obstacles upd|roughness|truth] [--goal-distance-m M]\n"
    "                     [--expect FILE.csv [--tolerance T]] [--config FILE.ini]\n"
    "                     [--nav-config FILE.ini] [--all-pictures] [--quiet]\n"
    "  Drives the simulated Dune (as `upd navigate`) through N generated worlds with the seeds\n"
    "  S .. S+N-1 and writes into DIR (created if missing; both files rewritten after every world):\n"
    "    worlds.csv    one row per world: seed, outcome (success, collision, timeout, stuck),\n"
    "                  failure category, time, path, optimal path, ratios, min clearance\n"
    "    summary.json  success_rate, collisions, timeouts, time_ratio, path_ratio,\n"
    "                  min_clearance_m, failures per category\n"
    "    failures/seed_S/  path_map.png, path_truth.png, trajectory.csv, summary.json of\n"
    "                  every world that failed (worlds/seed_S/ for every world with\n"
    "                  --all-pictures)\n"
    "  Exit status: 0 done (or the run agrees with --expect), 3 the run differs from --expect,\n"
    "  1 error, 2 bad usage.\n\n"
    "options:\n"
    "  --worlds N          number of worlds (required, >= 1)\n"
    "  --output DIR        output directory (required)\n"
    "  --seed S            first world's seed (default 1)\n"
    "  --difficulty D      easy, default (default) or hard\n"
    "  --obstacles M       upd (default), roughness (the baseline) or truth (the oracle: the\n"
    "                      camera's points labelled with the ground truth)\n"
    "  --goal-distance-m M start to goal (default 10)\n"
    "  --expect FILE       compare the outcomes (and the ratios of successes) with a worlds.csv\n"
    "  --tolerance T       allowed difference of the ratios with --expect (default 0.25)\n"
    "  --config FILE       robot config (default config/dune-kinect.ini)\n"
    "  --nav-config FILE   navigation config (default config/dune-nav.ini)\n"
    "  --all-pictures      the pictures of every world, successes too\n"
    "  --quiet             no progress lines\n";

namespace {

struct BenchOptions {
  int worlds = 0;
  std::string output;
  sim::WorldGenParams gen;
  nav::BenchPerception perception = nav::BenchPerception::Upd;
  std::optional<std::string> expect;
  double tolerance = 0.25;
  bool quiet = false, all_pictures = false;
};

BenchOptions parseOptions(const Args& args) {
  if (!args.positionals().empty()) throw UsageError("unexpected argument " + args.positionals()[0]);
  BenchOptions o;
  const auto n = args.integer("--worlds");
  if (!n) throw UsageError("--worlds N is required");
  if (*n < 1) throw UsageError("option --worlds = " + std::to_string(*n) + ": must be >= 1");
  o.worlds = *n;
  const auto out = args.str("--output");
  if (!out) throw UsageError("--output DIR is required");
  o.output = *out;
  if (const auto s = args.integer("--seed")) {
    if (*s < 0) throw UsageError("option --seed = " + std::to_string(*s) + ": must be >= 0");
    o.gen.seed = *s;
  }
  try {
    if (const auto d = args.str("--difficulty")) o.gen.difficulty = sim::parseDifficulty(*d);
    if (const auto m = args.str("--obstacles")) o.perception = nav::parseBenchPerception(*m);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("option ") + e.what());
  }
  if (const auto g = args.number("--goal-distance-m")) {
    if (!(*g >= 4.0)) throw UsageError("option --goal-distance-m = " + std::to_string(*g) + ": must be >= 4");
    o.gen.goal_distance_m = *g;
  }
  o.expect = args.str("--expect");
  if (const auto t = args.number("--tolerance")) {
    if (!(*t >= 0)) throw UsageError("option --tolerance = " + std::to_string(*t) + ": must be >= 0");
    o.tolerance = *t;
  }
  o.quiet = args.flag("--quiet");
  o.all_pictures = args.flag("--all-pictures");
  return o;
}

void printRow(int k, int n, const nav::BenchRow& r) {
  std::printf("[%3d/%d] seed %d (%s, %s): %-9s %5.1f s (x%.2f)  %5.2f m (x%.2f)  clearance %.2f m",
              k, n, r.seed, r.difficulty.c_str(), r.obstacles.c_str(), nav::toString(r.outcome),
              r.time_s, r.time_ratio, r.path_m, r.path_ratio, r.min_clearance_m);
  if (r.cause != nav::FailureCause::None) std::printf("  [%s]", nav::toString(r.cause));
  std::printf("  wall %.0f s\n", r.wall_s);
  std::fflush(stdout);
}

}  // namespace

int runBenchNav(const std::vector<std::string>& argv) {
  const Args args(argv,
                  {"--worlds", "--output", "--seed", "--difficulty", "--obstacles",
                   "--goal-distance-m", "--expect", "--tolerance", "--config", "--nav-config"},
                  {"--quiet", "--all-pictures"});
  const BenchOptions o = parseOptions(args);
  const nav::NavConfig config = loadNavConfigs(navConfigPaths(args));
  std::vector<nav::BenchRow> expected;
  if (o.expect) expected = nav::readBenchCsv(*o.expect);  // a bad file fails before the runs
  namespace fs = std::filesystem;
  OutputFolder out_folder(o.output);  // removed again, if empty, when the first world fails
  const nav::BenchParams params;
  std::vector<nav::BenchRow> rows;
  for (int k = 0; k < o.worlds; ++k) {
    sim::WorldGenParams gen = o.gen;
    gen.seed = o.gen.seed + k;
    const nav::BenchWorld world = nav::makeBenchWorld(gen, config.body, params);
    nav::ScenarioResult run;
    nav::BenchRow row = nav::runBenchWorld(world, config, o.perception, params, &run);
    row.seed = gen.seed;
    row.difficulty = sim::toString(gen.difficulty);
    rows.push_back(row);
    const bool failed = row.outcome != nav::BenchOutcome::Success;
    if (failed || o.all_pictures) {
      run.scenario = "seed " + std::to_string(gen.seed) + " " + row.difficulty;
      const fs::path dir = fs::path(o.output) / (failed ? "failures" : "worlds") /
                           ("seed_" + std::to_string(gen.seed));
      nav::writeScenarioOutputs(run, world.generated.world, config.body, dir.string());
    }
    nav::writeBenchCsv((fs::path(o.output) / "worlds.csv").string(), rows);
    io::writeJsonAtomically((fs::path(o.output) / "summary.json").string(),
                            nav::benchSummary(rows));
    out_folder.keep();
    if (!o.quiet) printRow(k + 1, o.worlds, row);
  }
  const nlohmann::json s = nav::benchSummary(rows);
  std::printf("%d worlds (%s, %s): success %.0f %%, %d collisions, %d timeouts, %d stuck; "
              "outputs in %s\n",
              o.worlds, sim::toString(o.gen.difficulty), nav::toString(o.perception),
              100.0 * s["success_rate"].get<double>(), s["collisions"].get<int>(),
              s["timeouts"].get<int>(), s["stuck"].get<int>(), o.output.c_str());
  if (!o.expect) return 0;
  const auto diffs = nav::compareBench(expected, rows, o.tolerance);
  for (const auto& d : diffs) std::printf("  differs from %s: %s\n", o.expect->c_str(), d.c_str());
  return diffs.empty() ? 0 : 3;
}

}  // namespace upd::app
