// The benchmark's options, its targets and the report it prints and writes as JSON: what every
// part of upd_bench shares.
#pragma once

#include <cmath>
#include <cstddef>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace upd::bench {

using json = nlohmann::json;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Median of v; NaN when v is empty.
double median(std::vector<double> v);

/// JSON number, or null for NaN / infinity (JSON has neither).
inline json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

struct Options {
  std::string data_dir = UPD_SHARED_DATA_DIR;
  std::string json_path;
  bool quick = false;
  bool frames_only = false;  // the frame pipeline timings alone (one core, two cores, memory)
  std::string only;          // "paper", "sensor-rate" or "octree": that table alone
  int repeats = 15;
  // The user's frames (--frame), after the three of the report: organized clouds or depth PNGs.
  std::vector<std::string> frames;
  std::string intrinsics;     // a depth PNG's calibration YAML ("" the Kinect's)
  double depth_scale = 0.001;  // a depth PNG's metres per unit
  float up[3] = {0.f, -1.f, 0.f};  // gravity-up in the user's frames (a level camera)
  bool up_given = false;           // --up (else a calibration's local_transform gives it)
};

// The performance targets the report checks (docs/PERFORMANCE.md, "Targets").
constexpr double kFrameBudgetMs = 33.0;
constexpr double kMinSpeedupVsPcl = 100.0;
constexpr double kMaxDmRatio = 1.5;         // t(d_m = 2) / t(d_m = 0.25)
constexpr double kMaxPerPointGrowth = 1.5;  // time per point at x16 / at x1
constexpr double kMaxMeanDzeta = 0.005;
constexpr double kMinSameLabel = 0.995;
constexpr double kMinTwoCoreSpeedup = 1.7;
constexpr double kMaxPeakMemoryMb = 300.0;
constexpr double kMinPaperSpeedupVsPcl = 300.0;      // the paper's whole pipeline, PCL / ours
constexpr double kMaxPreprocessShare = 0.25;         // of our paper pipeline's frame
constexpr double kMaxSensorRateOverIntegral = 0.2;   // sensor-rate path / PCL integral normals
constexpr double kMinPipelineTwoCoreSpeedup = 1.8;   // those two pipelines' second core

struct Target {
  std::string name;
  double value = kNaN;
  double limit = kNaN;
  bool upper_bound = true;  // value <= limit (else value >= limit)
  std::string unit;
  std::string note;  // printed after it (the machine's own second core beside ours)
  bool met() const {
    return std::isfinite(value) && (upper_bound ? value <= limit : value >= limit);
  }
};

/// The JSON report being built and the targets checked so far.
class Report {
 public:
  json root = json::object();
  std::vector<Target> targets;

  void target(const std::string& name, double value, double limit, bool upper,
              const std::string& unit, const std::string& note = "") {
    targets.push_back({name, value, limit, upper, unit, note});
  }
};

/// A line of dashes between the report's tables.
void printRule();

/// Prints a table's title between two rules.
void printTitle(const char* title);

/// Peak resident memory of this process [MB].
double peakRssMb();

/// Sustained copy bandwidth of this machine [GB/s] (read + write counted), for the floor.
double copyBandwidthGBs();

/// What this machine's second core gives at the moment, as a peer for the pipelines' second
/// core: work of compute alone (independent multiply-adds, no memory, no serial part) in 24
/// parallel regions of equal halves, as many regions a run as a frame's stages, run on one
/// thread and then on two before each pair of blocks of a timing loop. Where the second CPU is
/// shared (a VM's vCPU whose sibling or host is busy), a region waits for the slower thread
/// and the probe falls below 2 with the pipelines; the two read together tell the code's
/// scaling from the machine's.
///
/// Beside it, the round trip of a cache line between the two threads (one writes, the other
/// answers, a few thousand times): what every hand-over of data between the cores costs. On a
/// VM the host places the two vCPUs near each other (~80 ns on an AMD EPYC VM, as within one
/// L3) or apart (~340 ns on the same VM a minute later), and a pipeline whose stages read what
/// the other thread wrote gains less from its second core when they are apart, where the
/// compute probe does not move.
class CoreProbe {
 public:
  /// One run on one thread and one on two, and a round trip.
  void sample();
  /// median(one thread) / median(two threads); NaN before the first sample.
  double speedup() const;
  /// The median round trip of a cache line between the two threads [ns]; NaN before the first
  /// sample, or when the two threads shared one CPU (no answer within a few milliseconds).
  double roundTripNs() const;
  /// Both into a case's JSON: machine_two_core_speedup, machine_core_round_trip_ns.
  void addTo(json& c) const;

 private:
  std::vector<double> one_ms_, two_ms_, trip_ns_;
};

/// "(machine xS, a line between the cores T ns)": the probe's speedup and round trip, for a
/// target's note.
std::string machineNote(const CoreProbe& probe);

/// The machine, the compiler and the OpenMP wait policy: printed and stored under "machine".
void describeMachine(Report& report, double bandwidth);

/// The bandwidth floor of a frame, the targets table and, with --json, the JSON file.
int finish(Report& report, const Options& o, double bandwidth);

}  // namespace upd::bench
