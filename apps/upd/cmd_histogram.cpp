// `upd histogram`: the distribution of zeta at several d_m (the paper's Figs. 4 and 7) as a PNG.
#include "cli.h"
#include "commands.h"

#include "upd/core/pipeline.h"
#include "upd/io/cloud_io.h"
#include "upd/nav/figure.h"
#include "run_config.h"

#include <cstdio>
#include <sstream>

namespace upd::app {

const char* const kHistogramUsage =
    "usage: upd histogram INPUT --radii D1,D2,... --output FILE.png [options]\n"
    "  Scores INPUT (.pcd, .ply, .xyz; a scored PLY is re-scored from its x y z) at each d_m\n"
    "  and plots the share of points per zeta bin, one line per d_m. See docs/FIGURES.md.\n\n"
    "options:\n"
    "  --radii D1,D2,...     UPD search radii d_m [m] (required), e.g. 0.1,0.5,1.0\n"
    "  --output FILE.png     the plot (required)\n"
    "  --config FILE.ini     pipeline parameters (default: the built-in defaults)\n"
    "  --bins N              zeta bins over [min(0.70, lowest zeta), 1] (default 30)\n"
    "  --size WxH            image size in pixels (default 1000x620)\n"
    "  --title TEXT          caption above the plot (default: INPUT)\n";

namespace {

std::vector<double> parseRadii(const std::string& s) {
  std::vector<double> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) {
    std::size_t used = 0;
    double v = 0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size() || used == 0 || !(v > 0))
      throw UsageError("--radii '" + s + "': expected positive radii in metres, e.g. 0.1,0.5,1.0");
    out.push_back(v);
  }
  if (out.empty()) throw UsageError("--radii: no radius given");
  return out;
}

}  // namespace

int runHistogram(const std::vector<std::string>& argv) {
  const Args args(argv, {"--radii", "--output", "--config", "--bins", "--size", "--title"}, {});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one INPUT file");
  const std::string input = args.positionals()[0];
  const auto output = args.str("--output");
  if (!output) throw UsageError("--output FILE.png is required");
  const auto radii_arg = args.str("--radii");
  if (!radii_arg) throw UsageError("--radii D1,D2,... is required");
  const std::vector<double> radii = parseRadii(*radii_arg);
  nav::HistogramOptions opt;
  if (const auto v = args.integer("--bins")) opt.bins = *v;
  if (const auto size = args.str("--size")) std::tie(opt.width, opt.height) = parseImageSize(*size);
  opt.title = args.str("--title").value_or(input);
  core::PipelineParams params;
  if (const auto cfg = args.str("--config")) params = loadRunConfig(*cfg).observer.pipeline;

  const core::PointCloud cloud = io::readCloud(input);
  std::vector<nav::ZetaSeries> series;
  for (double r : radii) {
    params.upd.radius_m = r;
    params.validate();
    const core::PipelineResult res = core::runPipeline(cloud, params);
    series.push_back({r, res.upd.zeta});
  }
  nav::drawZetaHistogram(series, opt, *output);
  std::printf("%s: zeta at %zu radii plotted to %s\n", input.c_str(), radii.size(), output->c_str());
  return 0;
}

}  // namespace upd::app
