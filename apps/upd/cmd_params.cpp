// `upd params`: every parameter of the library with its ini section, key, default and meaning,
// taken from the structs' visit() (the one place the defaults are written). With --markdown it
// prints docs/PARAMETERS.md; with --ini an ini file holding every default.
#include "cli.h"
#include "commands.h"

#include "run_config.h"
#include "upd/core/floor_plane.h"
#include "upd/nav/nav_config.h"

#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

namespace upd::app {

const char* const kParamsUsage =
    "usage: upd params [--markdown | --ini | --nav-ini]\n"
    "  Lists every parameter: ini section, key, default and meaning (robot config, then\n"
    "  the navigation config of upd navigate).\n"
    "  --markdown  as the tables in docs/PARAMETERS.md (the default)\n"
    "  --ini       the robot config as an ini file holding every default (a starting point)\n"
    "  --nav-ini   the navigation config likewise\n";

namespace {

struct Printer {
  std::ostream& os;
  bool markdown;
  template <class T>
  void operator()(const char* key, const T& value, const char* doc) {
    std::ostringstream v;
    if constexpr (std::is_same_v<T, bool>) {
      v << (value ? "true" : "false");
    } else if constexpr (std::is_same_v<T, Eigen::Vector3f>) {
      v << value.x() << "," << value.y() << "," << value.z();
    } else {
      v << value;
    }
    if (markdown) {
      os << "| `" << key << "` | `" << v.str() << "` | " << doc << " |\n";
    } else {
      os << "; " << doc << "\n" << key << " = " << v.str() << "\n";
    }
  }
  void angleDeg(const char* key, const double& radians, const char* doc) {
    (*this)(key, radians * core::kRadToDeg, doc);
  }
  template <class E, std::size_t N>
  void choice(const char* key, const E& value, const core::EnumName<E> (&names)[N], const char* doc) {
    const char* name = core::enumName(names, value);
    (*this)(key, std::string(name != nullptr ? name : "?"), doc);
  }
};

}  // namespace

namespace {

template <class Sections>
void printSections(std::ostream& os, bool markdown, Sections&& for_each) {
  for_each([&](const char* name, const char* what, auto& params) {
    if (markdown) {
      os << "\n### [" << name << "]\n\n" << what << "\n\n| key | default | meaning |\n|---|---|---|\n";
    } else {
      os << "\n[" << name << "]\n";
    }
    Printer p{os, markdown};
    params.visit(p);
    if (std::string(name) == "ClassifyParams") {  // read beside the struct: a file, not a number
      p("classifier", std::string(),
        "the learned classifier's model file (`upd train`; relative to the config file); when "
        "set it labels the points instead of the thresholds above (empty: the thresholds)");
    }
  });
}

void printRobotParams(std::ostream& os, bool markdown) {
  RunConfig defaults;
  printSections(os, markdown, [&](auto&& f) { forEachSection(defaults, f); });
}

void printNavParams(std::ostream& os, bool markdown) {
  nav::NavConfig defaults;
  printSections(os, markdown, [&](auto&& f) { nav::forEachNavSection(defaults, f); });
}

}  // namespace

void printAllParams(std::ostream& os, bool markdown) {
  if (markdown) os << "\n## Robot config (`--config`, e.g. `config/dune-kinect.ini`)\n";
  printRobotParams(os, markdown);
  if (markdown) {
    os << "\n## Navigation config (`upd navigate --nav-config`, e.g. `config/dune-nav.ini`)\n";
  }
  printNavParams(os, markdown);
  if (markdown) os << "\n## Mount calibration (`upd calibrate-mount --floor-config`)\n";
  core::FloorPlaneParams floor;
  printSections(os, markdown, [&](auto&& f) {
    f("FloorPlaneParams", "How the floor is found under the camera.", floor);
  });
}

int runParams(const std::vector<std::string>& argv) {
  const Args args(argv, {}, {"--markdown", "--ini", "--nav-ini"});
  if (!args.positionals().empty()) throw UsageError("upd params takes no positional argument");
  if (args.flag("--markdown") + args.flag("--ini") + args.flag("--nav-ini") > 1) {
    throw UsageError("choose one of --markdown, --ini and --nav-ini");
  }
  if (args.flag("--ini")) {
    std::cout << "; UPD-Nav robot config with every default (upd params --ini)\n";
    printRobotParams(std::cout, false);
  } else if (args.flag("--nav-ini")) {
    std::cout << "; UPD-Nav navigation config with every default (upd params --nav-ini);\n"
                 "; [NavigatorParams] also needs ptg_ini (see config/dune-nav.ini)\n";
    printNavParams(std::cout, false);
  } else {
    printAllParams(std::cout, true);
  }
  return 0;
}

}  // namespace upd::app
