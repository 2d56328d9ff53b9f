// `upd scene`: writes one of the generated test scenes (the paper's experiments) as a PLY
// cloud whose `label` property holds the ground truth.
#include "cli.h"
#include "commands.h"

#include "upd/io/cloud_io.h"
#include "upd/sim/scenes.h"

#include <cstdio>

namespace upd::app {

const char* const kSceneUsage =
    "usage: upd scene NAME --output FILE.ply [--noise-m S] [--spacing-m S] [--seed N]\n"
    "  Writes a generated scene with a ground-truth `label` property per point\n"
    "  (0 traversable, 1 non-traversable, 2 unknown). NAME is one of:\n"
    "  corner, ramp, step, stairs, ditch, rocks (see docs/METHOD.md).\n\n"
    "options:\n"
    "  --output FILE.ply   where to write (required)\n"
    "  --noise-m S         Gaussian noise on every coordinate [m] (default 0)\n"
    "  --spacing-m S       sampling step [m] (default 0.01)\n"
    "  --seed N            noise seed (default 1)\n";

int runScene(const std::vector<std::string>& argv) {
  const Args args(argv, {"--output", "--noise-m", "--spacing-m", "--seed"}, {});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one scene NAME");
  const auto out = args.str("--output");
  if (!out) throw UsageError("--output FILE.ply is required");
  sim::SceneParams params;
  if (const auto v = args.number("--noise-m")) params.noise_m = *v;
  if (const auto v = args.number("--spacing-m")) params.spacing_m = *v;
  if (const auto v = args.integer("--seed")) params.seed = *v;
  const sim::Scene scene = sim::makeScene(args.positionals()[0], params);
  io::writePly(*out, scene.cloud, &scene.truth);
  std::printf("%s: %zu points -> %s\n", scene.name.c_str(), scene.cloud.size(), out->c_str());
  return 0;
}

}  // namespace upd::app
