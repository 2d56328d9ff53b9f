// The benchmark's files: worlds.csv (written and read back for the regression check),
// summary.json, and the comparison of a run with the expected rows (upd/nav/bench.h).
#include "upd/nav/bench.h"

#include "upd/core/version.h"
#include "upd/io/atomic_file.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace upd::nav {

namespace {

const char* const kCsvHeader =
    "seed,difficulty,obstacles,outcome,failure,time_s,path_m,optimal_path_m,optimal_time_s,"
    "time_ratio,path_ratio,min_clearance_m,collision_steps,final_distance_m,end,wall_s";

double mean(const std::vector<double>& v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

// NaN (no successes) is written as null.
nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

}  // namespace

nlohmann::json benchSummary(const std::vector<BenchRow>& rows) {
  std::vector<double> time_ratio, path_ratio, time_s;
  int collisions = 0, timeouts = 0, stuck = 0;
  double min_clearance = std::numeric_limits<double>::infinity(), wall = 0.0;
  std::map<std::string, int> causes;
  for (const BenchRow& r : rows) {
    wall += r.wall_s;
    min_clearance = std::min(min_clearance, r.min_clearance_m);
    switch (r.outcome) {
      case BenchOutcome::Success:
        time_ratio.push_back(r.time_ratio);
        path_ratio.push_back(r.path_ratio);
        time_s.push_back(r.time_s);
        break;
      case BenchOutcome::Collision: ++collisions; break;
      case BenchOutcome::Timeout: ++timeouts; break;
      case BenchOutcome::Stuck: ++stuck; break;
    }
    if (r.cause != FailureCause::None) ++causes[toString(r.cause)];
  }
  nlohmann::json j;
  j["upd_nav_version"] = core::version();
  j["worlds"] = rows.size();
  if (!rows.empty()) {
    j["difficulty"] = rows.front().difficulty;
    j["obstacles"] = rows.front().obstacles;
  }
  j["successes"] = time_ratio.size();
  j["success_rate"] = rows.empty() ? 0.0 : static_cast<double>(time_ratio.size()) / rows.size();
  j["collisions"] = collisions;
  j["timeouts"] = timeouts;
  j["stuck"] = stuck;
  j["time_ratio"] = number(mean(time_ratio));
  j["path_ratio"] = number(mean(path_ratio));
  j["mean_time_s"] = number(mean(time_s));
  j["min_clearance_m"] = number(min_clearance);
  j["failures"] = causes;
  j["wall_time_s"] = wall;
  return j;
}

void writeBenchCsv(const std::string& path, const std::vector<BenchRow>& rows) {
  io::writeFileAtomically(path, [&](std::ostream& os) {
    os << kCsvHeader << '\n' << std::fixed;
    for (const BenchRow& r : rows) {
      os << r.seed << ',' << r.difficulty << ',' << r.obstacles << ',' << toString(r.outcome)
         << ',' << toString(r.cause) << ',' << std::setprecision(1) << r.time_s << ','
         << std::setprecision(2) << r.path_m << ',' << r.optimal_path_m << ','
         << std::setprecision(1) << r.optimal_time_s << ',' << std::setprecision(3)
         << r.time_ratio << ',' << r.path_ratio << ',' << r.min_clearance_m << ','
         << r.collision_steps << ',' << std::setprecision(2) << r.final_distance_m << ','
         << r.end << ',' << std::setprecision(1) << r.wall_s << '\n';
    }
  });
}

namespace {

FailureCause parseCause(const std::string& s) {
  for (FailureCause c : {FailureCause::None, FailureCause::FalseObstacle,
                         FailureCause::MissedObstacle, FailureCause::Planning,
                         FailureCause::Navigator}) {
    if (s == toString(c)) return c;
  }
  throw std::invalid_argument("failure '" + s + "' unknown");
}

BenchRow parseRow(const std::vector<std::string>& f) {
  BenchRow r;
  r.seed = std::stoi(f[0]);
  r.difficulty = f[1];
  r.obstacles = f[2];
  r.outcome = parseBenchOutcome(f[3]);
  r.cause = parseCause(f[4]);
  r.time_s = std::stod(f[5]);
  r.path_m = std::stod(f[6]);
  r.optimal_path_m = std::stod(f[7]);
  r.optimal_time_s = std::stod(f[8]);
  r.time_ratio = std::stod(f[9]);
  r.path_ratio = std::stod(f[10]);
  r.min_clearance_m = std::stod(f[11]);
  r.collision_steps = std::stoi(f[12]);
  r.final_distance_m = std::stod(f[13]);
  r.end = f[14];
  r.wall_s = std::stod(f[15]);
  return r;
}

}  // namespace

std::vector<BenchRow> readBenchCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  if (!std::getline(in, line) || line != kCsvHeader) {
    throw std::runtime_error(path + ": line 1: not a bench-nav worlds.csv header");
  }
  std::vector<BenchRow> rows;
  for (int n = 2; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    std::vector<std::string> fields;
    std::stringstream ss(line);
    for (std::string f; std::getline(ss, f, ',');) fields.push_back(f);
    try {
      if (fields.size() != 16) throw std::invalid_argument("expected 16 fields");
      rows.push_back(parseRow(fields));
    } catch (const std::exception& e) {
      throw std::runtime_error(path + ": line " + std::to_string(n) + ": " + e.what());
    }
  }
  return rows;
}

std::vector<std::string> compareBench(const std::vector<BenchRow>& expected,
                                      const std::vector<BenchRow>& actual,
                                      double ratio_tolerance) {
  const auto key = [](const BenchRow& r) { return std::tie(r.seed, r.difficulty, r.obstacles); };
  std::vector<std::string> diffs;
  for (const BenchRow& e : expected) {
    const std::string name = "seed " + std::to_string(e.seed) + " (" + e.difficulty + ", " +
                             e.obstacles + ")";
    const auto a = std::find_if(actual.begin(), actual.end(),
                                [&](const BenchRow& r) { return key(r) == key(e); });
    if (a == actual.end()) {
      diffs.push_back(name + ": not run");
      continue;
    }
    if (a->outcome != e.outcome) {
      diffs.push_back(name + ": " + toString(a->outcome) + ", expected " + toString(e.outcome));
      continue;
    }
    if (e.outcome != BenchOutcome::Success) continue;
    for (const auto& [what, x, y] : {std::tuple{"time_ratio", a->time_ratio, e.time_ratio},
                                     std::tuple{"path_ratio", a->path_ratio, e.path_ratio}}) {
      if (std::abs(x - y) > ratio_tolerance) {
        std::ostringstream os;
        os << name << ": " << what << ' ' << x << ", expected " << y << " +- " << ratio_tolerance;
        diffs.push_back(os.str());
      }
    }
  }
  return diffs;
}

}  // namespace upd::nav
