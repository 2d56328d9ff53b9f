// `upd params`: every parameter of the library with its ini section, key, default and meaning,
// taken from the structs' visit() (the one place the defaults are written). With --markdown it
// prints docs/PARAMETERS.md; with --ini an ini file holding every default.
#include "cli.h"
#include "commands.h"

#include "run_config.h"

#include <cstdio>
#include <iostream>
#include <sstream>

namespace upd::app {

const char* const kParamsUsage =
    "usage: upd params [--markdown | --ini]\n"
    "  Lists every parameter: ini section, key, default and meaning.\n"
    "  --markdown  as the table in docs/PARAMETERS.md\n"
    "  --ini       as an ini file holding every default (a starting point for a config)\n";

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
    (*this)(key, radians * kRadToDeg, doc);
  }
};

}  // namespace

void printAllParams(std::ostream& os, bool markdown) {
  RunConfig defaults;
  forEachSection(defaults, [&](const char* name, const char* what, auto& params) {
    if (markdown) {
      os << "\n### [" << name << "]\n\n" << what << "\n\n| key | default | meaning |\n|---|---|---|\n";
    } else {
      os << "\n[" << name << "]\n";
    }
    Printer p{os, markdown};
    params.visit(p);
  });
}

int runParams(const std::vector<std::string>& argv) {
  const Args args(argv, {}, {"--markdown", "--ini"});
  if (!args.positionals().empty()) throw UsageError("upd params takes no positional argument");
  if (args.flag("--markdown") && args.flag("--ini")) {
    throw UsageError("choose one of --markdown and --ini");
  }
  if (args.flag("--ini")) std::cout << "; UPD-Nav parameters with their defaults (upd params --ini)\n";
  printAllParams(std::cout, !args.flag("--ini"));
  return 0;
}

}  // namespace upd::app
