#include "live_options.h"

#include "cli.h"
#include "nav_run_config.h"

#include "upd/nav/nav_config.h"

#include <cmath>
#include <sstream>

namespace upd::app {

namespace {

Eigen::Vector2d parseGoal(const std::string& text) {
  std::istringstream is(text);
  double x = 0, y = 0;
  char comma = 0;
  if (!(is >> x >> comma >> y) || comma != ',' || !(is >> std::ws).eof() || !std::isfinite(x) ||
      !std::isfinite(y)) {
    throw UsageError("option --navigate = '" + text + "': expected X,Y in metres");
  }
  return {x, y};
}

bool isIndex(const std::string& s) {
  return !s.empty() && s.size() < 4 && s.find_first_not_of("0123456789") == std::string::npos;
}

// `--kinect [INDEX]`: the index is optional, so it is taken out before the generic parser.
std::vector<std::string> takeKinect(const std::vector<std::string>& argv, LiveOptions& o) {
  std::vector<std::string> rest;
  for (std::size_t i = 0; i < argv.size(); ++i) {
    if (argv[i] != "--kinect") {
      rest.push_back(argv[i]);
      continue;
    }
    o.kinect = 0;
    if (i + 1 < argv.size() && isIndex(argv[i + 1])) o.kinect = std::stoi(argv[++i]);
  }
  return rest;
}

void checkOneSource(const LiveOptions& o) {
  const int n = !o.oni.empty() + !o.sensors.empty() + o.kinect.has_value();
  if (n > 1) throw UsageError("choose one source: --oni, --sensors or --kinect");
  if (!o.sensor_section.empty() && o.sensors.empty()) {
    throw UsageError("--sensor-section needs --sensors FILE.ini");
  }
}

}  // namespace

LiveOptions parseLiveOptions(const std::vector<std::string>& argv_in) {
  LiveOptions o;
  const std::vector<std::string> argv = takeKinect(argv_in, o);
  const Args args(argv,
                  {"--config", "--nav-config", "--oni", "--sensors", "--sensor-section",
                   "--navigate", "--frames", "--output", "--record", "--stale-timeout",
                   "--mount", "--base", "--screenshot"},
                  {"--view", "--auto-mount"});
  if (!args.positionals().empty()) throw UsageError("unexpected argument " + args.positionals()[0]);
  const NavConfigPaths configs = navConfigPaths(args);
  o.config_path = configs.robot;
  o.nav_path = configs.nav;
  o.oni = args.str("--oni").value_or("");
  o.sensors = args.str("--sensors").value_or("");
  o.sensor_section = args.str("--sensor-section").value_or("");
  o.max_frames = args.integer("--frames").value_or(0);
  if (o.max_frames < 0)
    throw UsageError("option --frames = " + std::to_string(o.max_frames) + ": must be >= 0");
  if (const auto g = args.str("--navigate")) o.goal = parseGoal(*g);
  o.out = args.str("--output");
  o.record = args.str("--record");
  o.stale_timeout_s = args.number("--stale-timeout").value_or(o.stale_timeout_s);
  if (!(o.stale_timeout_s > 0)) {
    throw UsageError("option --stale-timeout = " + std::to_string(o.stale_timeout_s) +
                     ": must be > 0 [s]");
  }
  o.view = args.flag("--view");
  o.screenshot = args.str("--screenshot");
  if (o.screenshot && !o.view) throw UsageError("option --screenshot needs --view");
  o.mount = args.str("--mount");
  o.auto_mount = args.flag("--auto-mount");
  if (o.mount && o.auto_mount) throw UsageError("choose one of --mount and --auto-mount");
  o.base = args.str("--base").value_or("sim");
  checkOneSource(o);
  return o;
}

}  // namespace upd::app
