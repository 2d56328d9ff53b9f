#include "report.h"

#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include "upd/core/stopwatch.h"
#include "upd/core/version.h"
#include "upd/io/json_io.h"

namespace core = upd::core;

namespace upd::bench {

double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

void printRule() { std::printf("%s\n", std::string(100, '-').c_str()); }

void printTitle(const char* title) {
  printRule();
  std::printf("%s\n", title);
  printRule();
}

double peakRssMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

double copyBandwidthGBs() {
  const std::size_t n = std::size_t(64) << 20;
  std::vector<char> a(n, 1), b(n, 2);
  double best = 0;
  for (int r = 0; r < 5; ++r) {
    const core::Stopwatch watch;
    std::memcpy(b.data(), a.data(), n);
    const double s = watch.elapsedMs() / 1e3;
    best = std::max(best, 2.0 * static_cast<double>(n) / s / 1e9);
    std::swap(a, b);
  }
  return best;
}

namespace {

// iters steps of four independent multiply-add chains, the sum of their ends (compute alone:
// no loads or stores in the loop).
double multiplyAddChains(std::int64_t iters, double seed) {
  double a = seed, b = seed + 0.25, c = seed + 0.5, d = seed + 0.75;
  for (std::int64_t i = 0; i < iters; ++i) {
    a = a * 0.9999999 + 1e-7;
    b = b * 0.9999998 + 2e-7;
    c = c * 0.9999997 + 3e-7;
    d = d * 0.9999996 + 4e-7;
  }
  return a + b + c + d;
}

// The probe's work: kProbeRounds parallel regions of kProbeSteps steps each, split over the
// team (~2 ms on one thread at a few GHz, in regions as short as the pipelines' stages: ~24 a
// frame of 5-15 ms).
constexpr int kProbeRounds = 24;
constexpr std::int64_t kProbeSteps = std::int64_t(1) << 16;
volatile double probe_sink = 0;

// The probe's work on the current number of threads [ms].
double timeProbe() {
  double ends[64] = {};
  const core::Stopwatch watch;
  for (int round = 0; round < kProbeRounds; ++round) {
#pragma omp parallel
    {
      const int team = omp_get_num_threads(), me = omp_get_thread_num();
      if (me < 64) ends[me] += multiplyAddChains(kProbeSteps / team, probe_sink + me);
    }
  }
  const double ms = watch.elapsedMs();
  double sum = 0;
  for (const double e : ends) sum += e;
  probe_sink = sum;
  return ms;
}

// The mean round trip of a cache line between the two threads of a team [ns]: thread 0 writes
// an odd number, thread 1 answers with the next even one, kTrips times. NaN when the team is not
// two threads, or when the answers do not come within kMaxMs (the two threads on one CPU, each
// answer waiting for the other's time slice).
double timeRoundTripNs() {
  constexpr int kTrips = 4000;
  constexpr double kMaxMs = 20;
  alignas(64) std::atomic<int> line{0};
  alignas(64) std::atomic<bool> give_up{false};
  double ns = kNaN;
#pragma omp parallel num_threads(2)
  {
    if (omp_get_num_threads() == 2) {
#pragma omp barrier
      if (omp_get_thread_num() == 0) {
        const core::Stopwatch watch;
        for (int i = 0; i < kTrips && !give_up.load(std::memory_order_relaxed); ++i) {
          line.store(2 * i + 1, std::memory_order_release);
          while (line.load(std::memory_order_acquire) != 2 * i + 2) {
            if (watch.elapsedMs() > kMaxMs) {
              give_up.store(true, std::memory_order_relaxed);
              break;
            }
          }
        }
        if (!give_up.load()) ns = watch.elapsedMs() * 1e6 / kTrips;
      } else {
        for (int i = 0; i < kTrips && !give_up.load(std::memory_order_relaxed); ++i) {
          while (line.load(std::memory_order_acquire) != 2 * i + 1) {
            if (give_up.load(std::memory_order_relaxed)) break;
          }
          line.store(2 * i + 2, std::memory_order_release);
        }
      }
    }
  }
  return ns;
}

}  // namespace

void CoreProbe::sample() {
  omp_set_num_threads(1);
  one_ms_.push_back(timeProbe());
  omp_set_num_threads(2);
  two_ms_.push_back(timeProbe());
  const double trip = timeRoundTripNs();
  if (std::isfinite(trip)) trip_ns_.push_back(trip);
}

double CoreProbe::speedup() const { return median(one_ms_) / median(two_ms_); }

double CoreProbe::roundTripNs() const { return median(trip_ns_); }

void CoreProbe::addTo(json& c) const {
  c["machine_two_core_speedup"] = num(speedup());
  c["machine_core_round_trip_ns"] = num(roundTripNs());
}

std::string machineNote(const CoreProbe& probe) {
  char text[64];
  std::snprintf(text, sizeof text, "(machine x%.2f, a line between the cores %.0f ns)",
                probe.speedup(), probe.roundTripNs());
  return text;
}

namespace {

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  }
  return "unknown";
}

// The other threads ready to run beside this one (/proc/stat's procs_running less this one),
// averaged over 20 looks 10 ms apart before the benchmark starts its own; NaN where it cannot be
// read. The load average would lag: a run right after another reads the first one's load.
double otherRunnable() {
  double sum = 0;
  int looks = 0;
  for (int i = 0; i < 20; ++i) {
    std::ifstream in("/proc/stat");
    std::string key;
    double running = 0;
    while (in >> key) {
      if (key == "procs_running" && in >> running) {
        sum += running - 1, ++looks;
        break;
      }
      in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return looks > 0 ? sum / looks : kNaN;
}

}  // namespace

void describeMachine(Report& report, double bandwidth) {
  // The OpenMP wait policy changes the two-core timings: threads woken from sleep for each
  // parallel region (passive) cost more than threads that spin a while first (the default).
  const char* policy_env = std::getenv("OMP_WAIT_POLICY");
  const std::string policy = policy_env && *policy_env ? policy_env : "default";
  const double others = otherRunnable();
  report.root["machine"] = {{"cpu", cpuModel()},
                            {"logical_cpus", omp_get_num_procs()},
                            {"copy_bandwidth_GBps", bandwidth},
                            {"compiler", __VERSION__},
                            {"omp_wait_policy", policy},
                            {"upd_nav_version", core::version()},
                            {"other_runnable_threads_at_start", num(others)}};
  std::printf("machine: %s, %d logical CPUs, copy bandwidth %.1f GB/s, OMP_WAIT_POLICY %s; "
              "UPD-Nav %s\n",
              cpuModel().c_str(), omp_get_num_procs(), bandwidth, policy.c_str(), core::version());
  // Other jobs on the CPUs slow both sides and make the two-core figures meaningless.
  if (others > 0.3) {
    std::printf("note: %.1f other threads ready to run on average at the start: other jobs share "
                "the CPUs; the times, and the two-core figures most, mean little "
                "(docs/PERFORMANCE.md, \"The machine\")\n",
                others);
  }
}

int finish(Report& report, const Options& o, double bandwidth) {
  json& root = report.root;
  // The memory-bandwidth floor of a frame: read x, y, z once, write the per-pixel results once
  // (normal 12 B, curvature 4, r 12, zeta 4, k 4, label 1, cost 4, slope 4 = 45 B).
  const double floor_bytes = 307200.0 * (12 + 45);
  root["bandwidth_floor"] = {{"bytes_per_frame", floor_bytes},
                             {"copy_bandwidth_GBps", bandwidth},
                             {"floor_ms", floor_bytes / (bandwidth * 1e9) * 1e3}};

  printTitle("Targets");
  json tj = json::array();
  std::size_t met = 0;
  for (const Target& t : report.targets) {
    std::printf("  [%s] %-62s %10.4g %s %-6g %s%s%s\n", t.met() ? " met  " : "NOT MET",
                t.name.c_str(), t.value, t.upper_bound ? "<=" : ">=", t.limit, t.unit.c_str(),
                t.note.empty() ? "" : " ", t.note.c_str());
    tj.push_back({{"name", t.name},
                  {"value", num(t.value)},
                  {"limit", t.limit},
                  {"bound", t.upper_bound ? "<=" : ">="},
                  {"unit", t.unit},
                  {"met", t.met()}});
    if (!t.note.empty()) tj.back()["note"] = t.note;
    met += t.met() ? 1 : 0;
  }
  std::printf("%zu of %zu targets met; memory-bandwidth floor of a frame %.2f ms\n", met,
              report.targets.size(), floor_bytes / (bandwidth * 1e9) * 1e3);
  root["targets"] = tj;
  root["targets_met"] = met;
  root["targets_total"] = report.targets.size();
  if (!o.json_path.empty()) {
    io::writeJsonAtomically(o.json_path, root);
    std::printf("report written to %s\n", o.json_path.c_str());
  }
  return 0;
}

}  // namespace upd::bench
