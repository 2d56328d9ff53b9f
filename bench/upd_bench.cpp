// upd_bench: the fast paths (fast_normals.h, fast_upd.h) timed against the exact path and the
// PCL pipeline of the paper, on real and generated data, with the targets of GitHub issue 5.
//
// Usage: upd_bench [--data DIR] [--json OUT.json] [--quick] [--frames-only] [--repeats N]
//   --data DIR   the shared real data (default: the build's UPD_SHARED_DATA_DIR); a missing
//                file makes its case "skipped" in the report, never a failure
//   --json OUT   also write the report as JSON (the same numbers as the printed tables)
//   --quick      skip the PCL peer and use fewer exact samples (minutes instead of ~15)
//   --frames-only  only the frame pipeline timings (one core, two cores, memory): seconds
//   --repeats N  timed runs per case for the medians (default 15; big clouds use fewer)
//
// What is timed, per case (medians over the runs after one warm-up run):
//  - frame pipeline (organized 640 x 480): depth image (or organized cloud) -> normals -> UPD
//    -> labels -> map update, every pixel scored, on one core and on two;
//  - PCL settings: voxel 0.02 m, normals 0.05 m, d_m 0.5 m on both sides: our fast path, our
//    exact path and the PCL peer (run once: it takes seconds);
//  - normals alone: computeNormalsOrganized against PCL's IntegralImageNormalEstimation;
//  - the LiDAR scan, the corner, and generated clouds of growing size and growing d_m.
// Agreement with the exact path is measured on the same pre-processed cloud: exact normals for
// every point and the exact UPD for every point or, where that would take minutes, for an evenly
// spaced sample of points (the sample size is printed). The program exits 0 whether or not the
// targets are met: the report says which are.
#include "pcl_peer.h"
#include "upd/core/camera.h"
#include "upd/core/classify.h"
#include "upd/core/fast_normals.h"
#include "upd/core/fast_upd.h"
#include "upd/core/kdtree.h"
#include "upd/core/pipeline.h"
#include "upd/core/render.h"
#include "upd/core/scenes.h"
#include "upd/core/terrain.h"
#include "upd/io/cloud_io.h"

#ifdef UPD_BENCH_HAVE_MAPS
#include "upd/maps/grid_fusion.h"
#include "upd/maps/traversability_grid.h"
#endif

#include <omp.h>
#include <sched.h>
#include <sys/resource.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace upd::bench {
namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

/// JSON number, or null for NaN / infinity (JSON has neither).
json num(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

struct Options {
  std::string data_dir = UPD_SHARED_DATA_DIR;
  std::string json_path;
  bool quick = false;
  bool frames_only = false;  // the frame pipeline timings alone (one core, two cores, memory)
  int repeats = 15;
};

// ---------------------------------------------------------------------------------------------
// Targets of issue 5.
constexpr double kFrameBudgetMs = 33.0;
constexpr double kMinSpeedupVsPcl = 100.0;
constexpr double kMaxDmRatio = 1.5;         // t(d_m = 2) / t(d_m = 0.25)
constexpr double kMaxPerPointGrowth = 1.5;  // time per point at x16 / at x1
constexpr double kMaxMeanDzeta = 0.005;
constexpr double kMinSameLabel = 0.995;
constexpr double kMinTwoCoreSpeedup = 1.7;
constexpr double kMaxPeakMemoryMb = 300.0;

struct Target {
  std::string name;
  double value = kNaN;
  double limit = kNaN;
  bool upper_bound = true;  // value <= limit (else value >= limit)
  std::string unit;
  bool met() const {
    return std::isfinite(value) && (upper_bound ? value <= limit : value >= limit);
  }
};

// ---------------------------------------------------------------------------------------------
// Agreement of a fast result with the exact path on the same cloud.

struct ExactReference {
  std::vector<std::size_t> index;  // the compared points (all finite points, or a sample)
  UpdResult upd;                   // exact UPD at those points
  Classification classes;
  double normals_ms = 0, upd_ms = 0;
  std::size_t finite = 0;
};

// Exact normals for every point; the exact UPD (computeUpd's sums, eqs. 6-8) for every finite
// point when that is affordable, else for max_samples evenly spaced finite points.
ExactReference exactReference(const PointCloud& cloud, const PipelineParams& params,
                              std::size_t max_samples) {
  ExactReference ref;
  const Eigen::Vector3f up = params.unitUp();
  auto t0 = Clock::now();
  const KdTree tree(cloud);
  const Normals normals = computeNormals(cloud, tree, params.normals, up);
  ref.normals_ms = msSince(t0);
  std::vector<std::size_t> finite;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.isFinite(i)) finite.push_back(i);
  }
  ref.finite = finite.size();
  const std::size_t stride =
      std::max<std::size_t>(1, (finite.size() + max_samples - 1) / max_samples);
  for (std::size_t j = 0; j < finite.size(); j += stride) ref.index.push_back(finite[j]);
  const std::size_t n = ref.index.size();
  ref.upd = UpdResult::unscored(n);
  t0 = Clock::now();
  if (stride == 1) {
    const UpdResult all = computeUpd(cloud, tree, normals, params.upd);
    for (std::size_t q = 0; q < n; ++q) {
      const std::size_t i = ref.index[q];
      ref.upd.rx[q] = all.rx[i], ref.upd.ry[q] = all.ry[i], ref.upd.rz[q] = all.rz[i];
      ref.upd.zeta[q] = all.zeta[i], ref.upd.k[q] = all.k[i];
    }
  } else {
    // computeUpd's loop, for the sampled points only.
    const auto radius = static_cast<float>(params.upd.radius_m);
#pragma omp parallel
    {
      std::vector<std::uint32_t> nb;
#pragma omp for schedule(dynamic, 8)
      for (std::ptrdiff_t qq = 0; qq < static_cast<std::ptrdiff_t>(n); ++qq) {
        const auto q = static_cast<std::size_t>(qq);
        tree.radiusSearch(cloud.point(ref.index[q]), radius, nb);
        double sx = 0, sy = 0, sz = 0;
        std::uint32_t k = 0;
        for (const std::uint32_t j : nb) {
          if (!normals.isValid(j)) continue;
          sx += normals.nx[j], sy += normals.ny[j], sz += normals.nz[j];
          ++k;
        }
        if (k < static_cast<std::uint32_t>(params.upd.min_neighbors)) continue;
        ref.upd.rx[q] = static_cast<float>(sx);
        ref.upd.ry[q] = static_cast<float>(sy);
        ref.upd.rz[q] = static_cast<float>(sz);
        ref.upd.zeta[q] = static_cast<float>(std::sqrt(sx * sx + sy * sy + sz * sz) / k);
        ref.upd.k[q] = k;
      }
    }
  }
  for (std::size_t q = 0; q < n; ++q) ref.upd.invalid += ref.upd.isValid(q) ? 0 : 1;
  ref.upd_ms = msSince(t0);
  ref.classes = classify(ref.upd, up, params.classify);
  return ref;
}

struct Agreement {
  std::size_t compared = 0, finite = 0, both_valid = 0, validity_differs = 0;
  double mean_abs_dzeta = kNaN, max_abs_dzeta = kNaN, same_label = kNaN;
  double exact_normals_ms = kNaN, exact_upd_ms = kNaN;
  bool met() const {
    return std::isfinite(mean_abs_dzeta) && mean_abs_dzeta <= kMaxMeanDzeta &&
           same_label >= kMinSameLabel;
  }
  json toJson() const {
    return {{"points_compared", compared},
            {"finite_points", finite},
            {"sampled", compared < finite},
            {"both_scored", both_valid},
            {"scored_by_one_only", validity_differs},
            {"mean_abs_dzeta", num(mean_abs_dzeta)},
            {"max_abs_dzeta", num(max_abs_dzeta)},
            {"same_label_fraction", num(same_label)},
            {"exact_normals_ms", num(exact_normals_ms)},
            {"exact_upd_ms", num(exact_upd_ms)},
            {"met", met()}};
  }
};

// Compares the UPD of cloud's points in `fast` (any method) with the exact reference.
Agreement agreement(const ExactReference& ref, const UpdResult& fast,
                    const PipelineParams& params) {
  Agreement a;
  a.compared = ref.index.size();
  a.finite = ref.finite;
  a.exact_normals_ms = ref.normals_ms;
  a.exact_upd_ms = ref.upd_ms;
  UpdResult sub;
  const std::size_t n = ref.index.size();
  sub.rx.resize(n), sub.ry.resize(n), sub.rz.resize(n), sub.zeta.resize(n), sub.k.resize(n);
  for (std::size_t q = 0; q < n; ++q) {
    const std::size_t i = ref.index[q];
    sub.rx[q] = fast.rx[i], sub.ry[q] = fast.ry[i], sub.rz[q] = fast.rz[i];
    sub.zeta[q] = fast.zeta[i], sub.k[q] = fast.k[i];
  }
  const Classification cls = classify(sub, params.unitUp(), params.classify);
  double sum = 0, worst = 0;
  std::size_t same = 0;
  for (std::size_t q = 0; q < n; ++q) {
    same += cls.label[q] == ref.classes.label[q] ? 1 : 0;
    const bool ve = ref.upd.isValid(q), vf = sub.isValid(q);
    if (ve != vf) ++a.validity_differs;
    if (!ve || !vf) continue;
    const double d = std::abs(static_cast<double>(ref.upd.zeta[q]) - sub.zeta[q]);
    sum += d;
    worst = std::max(worst, d);
    ++a.both_valid;
  }
  if (a.both_valid > 0) {
    a.mean_abs_dzeta = sum / static_cast<double>(a.both_valid);
    a.max_abs_dzeta = worst;
  }
  if (n > 0) a.same_label = static_cast<double>(same) / static_cast<double>(n);
  return a;
}

// ---------------------------------------------------------------------------------------------
// The map update stage: the scored points into the 2.5D traversability grid, world frame.

class MapStage {
 public:
  explicit MapStage(const Eigen::Isometry3f& pose_world_cloud) : pose_(pose_world_cloud) {
#ifdef UPD_BENCH_HAVE_MAPS
    maps::GridParams gp;
    gp.cell_size_m = 0.05;
    gp.extent_m = 20.0;
    gp.follow_robot = false;
    gp.center_x_m = pose_.translation().x();
    gp.center_y_m = pose_.translation().y();
    grid_.emplace(gp);
#endif
  }
  static const char* kind() {
#ifdef UPD_BENCH_HAVE_MAPS
    return "upd::maps::integrateScan into a 20 x 20 m TraversabilityGrid of 0.05 m cells";
#else
    return "per-point binning into a 20 x 20 m grid of 0.05 m cells (libs/maps not built)";
#endif
  }
  void update(const PipelineResult& r, double time_s) {
    // Into the world frame (upd::transformCloud: vectorized, into the buffers of the last frame).
    transformCloud(r.cloud, pose_.cast<double>(), world_);
    const Eigen::Vector3f t = pose_.translation();
#ifdef UPD_BENCH_HAVE_MAPS
    maps::integrateScan(*grid_, maps::viewPoints(world_, r.classes, &r.upd),
                        Eigen::Vector2d(t.x(), t.y()), time_s, fusion_);
#else
    (void)time_s;
    constexpr int kSide = 400;
    counts_.assign(2 * kSide * kSide, 0);
    for (std::size_t i = 0; i < world_.size(); ++i) {
      const Label l = r.classes.label[i];
      if (l == Label::Unknown) continue;
      const int cx = static_cast<int>(std::floor((world_.x[i] - t.x()) / 0.05f)) + kSide / 2;
      const int cy = static_cast<int>(std::floor((world_.y[i] - t.y()) / 0.05f)) + kSide / 2;
      if (cx < 0 || cy < 0 || cx >= kSide || cy >= kSide) continue;
      ++counts_[2 * (cy * kSide + cx) + (l == Label::NonTraversable ? 1 : 0)];
    }
#endif
  }

 private:
  Eigen::Isometry3f pose_;
  PointCloud world_;
#ifdef UPD_BENCH_HAVE_MAPS
  std::optional<maps::TraversabilityGrid> grid_;
  maps::FusionParams fusion_;
#else
  std::vector<std::uint32_t> counts_;
#endif
};

// ---------------------------------------------------------------------------------------------
// Inputs.

struct Frame {
  std::string name, source;
  bool available = false;
  std::string skip_reason;
  PointCloud cloud;                 // organized, camera frame
  std::optional<DepthImage> depth;  // the generated frame starts from its depth image
  CameraIntrinsics intrinsics;
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();
  Eigen::Isometry3f pose_world_cloud = Eigen::Isometry3f::Identity();
};

std::optional<std::string> dataFile(const Options& o, const std::string& rel) {
  const auto p = std::filesystem::path(o.data_dir) / rel;
  if (std::filesystem::exists(p)) return p.string();
  return std::nullopt;
}

Frame pcdFrame(const Options& o, const std::string& name, const std::string& rel,
               const Eigen::Vector3f& up) {
  Frame f;
  f.name = name;
  f.source = "../shared/data/" + rel;
  f.up = up.normalized();
  const auto path = dataFile(o, rel);
  if (!path) {
    f.skip_reason = "file not found: " + (std::filesystem::path(o.data_dir) / rel).string();
    return f;
  }
  f.cloud = io::readCloud(*path);
  f.available = f.cloud.isOrganized();
  if (!f.available) f.skip_reason = "not an organized cloud";
  // World frame for the map: up -> +z, camera at the origin.
  f.pose_world_cloud.linear() =
      Eigen::Quaternionf::FromTwoVectors(f.up, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  return f;
}

Frame generatedFrame() {
  Frame f;
  f.name = "generated_kinect";
  f.source =
      "makeWorld(\"mixed\") rendered by a simulated Kinect 640x480, fx = fy = 525, "
      "camera 0.6 m high looking 3.5 m ahead, axial noise 1.2e-3 z^2, range 0.4-5 m";
  const WorldSpec world = makeWorld("mixed");
  const Eigen::Isometry3d pose = cameraPoseLookingAt({1.0, 0.3, 0.6}, {4.5, -0.4, 0.0});
  DepthNoise noise;
  noise.max_range_m = 5.0;
  const RenderedScene rs = renderScene(world.terrain, pose, f.intrinsics, noise, 7);
  f.depth = rs.depth;
  f.cloud = rs.scene.cloud;
  f.up = rs.scene.up.normalized();
  f.pose_world_cloud = rs.pose_world_camera.cast<float>();
  f.available = true;
  return f;
}

// ---------------------------------------------------------------------------------------------
// Timing helpers.

struct FrameTiming {
  double total_ms = kNaN;
  json stages;
  std::size_t scored = 0, points = 0;
};

// The frame pipeline: depth image (when there is one) -> cloud -> runPipeline -> map update.
// One loop keeps its cloud, result and map from frame to frame, as a sensor loop does: once
// warm, a frame allocates nothing.
class FrameLoop {
 public:
  FrameLoop(const Frame& f, const PipelineParams& params)
      : f_(f), params_(params), map_(f.pose_world_cloud) {}

  // One frame; its timings are kept when record.
  void run(bool record) {
    const auto t0 = Clock::now();
    const PointCloud* input = &f_.cloud;
    if (f_.depth) {
      depthToCloud(*f_.depth, f_.intrinsics, converted_);
      input = &converted_;
    }
    const double t_convert = msSince(t0);
    runPipeline(*input, params_, r_);
    const auto t_map = Clock::now();
    map_.update(r_, 0.1 * static_cast<double>(++frames_));
    const double map_time = msSince(t_map);
    const double t_total = msSince(t0);
    if (!record) return;
    total_.push_back(t_total);
    convert_.push_back(t_convert);
    pre_.push_back(r_.timings.preprocess_ms);
    normals_.push_back(r_.timings.index_ms + r_.timings.normals_ms);
    upd_.push_back(r_.timings.upd_ms);
    classify_.push_back(r_.timings.classify_ms);
    map_ms_.push_back(map_time);
  }

  FrameTiming timing() const {
    FrameTiming t;
    t.total_ms = median(total_);
    t.stages = {
        {"depth_to_cloud_ms", num(median(convert_))}, {"preprocess_ms", num(median(pre_))},
        {"normals_ms", num(median(normals_))},        {"upd_ms", num(median(upd_))},
        {"classify_ms", num(median(classify_))},      {"map_update_ms", num(median(map_ms_))}};
    t.points = r_.cloud.size();
    t.scored = r_.cloud.size() - r_.upd.invalid;
    return t;
  }
  PipelineResult& result() { return r_; }

 private:
  const Frame& f_;
  PipelineParams params_;
  MapStage map_;
  PipelineResult r_;
  PointCloud converted_;
  int frames_ = 0;
  std::vector<double> total_, convert_, pre_, normals_, upd_, classify_, map_ms_;
};

// Keeps the calling thread on the CPU it runs on, for the one-core frames, and lets it go
// again. Unpinned, the scheduler moves it between this VM's two vCPUs after the two-core
// frames, and the one-core median rises by 20-30 % (cold caches, idle vCPUs waking up);
// pinned, one core is one core.
class PinnedToThisCpu {
 public:
  PinnedToThisCpu() {
    pinned_ = sched_getaffinity(0, sizeof saved_, &saved_) == 0;
    const int cpu = sched_getcpu();
    if (!pinned_ || cpu < 0) {
      pinned_ = false;
      return;
    }
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    pinned_ = sched_setaffinity(0, sizeof one, &one) == 0;
  }
  ~PinnedToThisCpu() {
    if (pinned_) sched_setaffinity(0, sizeof saved_, &saved_);
  }
  PinnedToThisCpu(const PinnedToThisCpu&) = delete;
  PinnedToThisCpu& operator=(const PinnedToThisCpu&) = delete;

 private:
  cpu_set_t saved_;
  bool pinned_ = false;
};

// repeats frames after a warm-up frame, at the current thread count (pinned to one CPU when
// that is 1).
FrameTiming timeFramePipeline(const Frame& f, const PipelineParams& params, int repeats,
                              PipelineResult* last = nullptr) {
  FrameLoop loop(f, params);
  for (int run = -1; run < repeats; ++run) {
    std::optional<PinnedToThisCpu> pin;
    if (omp_get_max_threads() == 1) pin.emplace();
    loop.run(run >= 0);
  }
  const FrameTiming t = loop.timing();
  if (last) *last = std::move(loop.result());
  return t;
}

// The same on one core and on two, frame by frame in turn: on a shared machine whose speed
// drifts, both medians then see the same conditions and their ratio is the second core's gain.
std::pair<FrameTiming, FrameTiming> timeOneAndTwoCores(const Frame& f, const PipelineParams& params,
                                                       int repeats,
                                                       PipelineResult* last = nullptr) {
  FrameLoop one(f, params), two(f, params);
  for (int run = -1; run < repeats; ++run) {
    omp_set_num_threads(1);
    {
      const PinnedToThisCpu pin;
      one.run(run >= 0);
    }
    omp_set_num_threads(2);
    two.run(run >= 0);
  }
  std::pair<FrameTiming, FrameTiming> t{one.timing(), two.timing()};
  if (last) *last = std::move(one.result());
  return t;
}

double timeMedian(const std::function<void()>& f, int repeats) {
  std::vector<double> v;
  for (int run = -1; run < repeats; ++run) {
    const auto t0 = Clock::now();
    f();
    if (run >= 0) v.push_back(msSince(t0));
  }
  return median(v);
}

double peakRssMb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

// Sustained copy bandwidth of this machine [GB/s] (read + write counted), for the floor.
double copyBandwidthGBs() {
  const std::size_t n = std::size_t(64) << 20;
  std::vector<char> a(n, 1), b(n, 2);
  double best = 0;
  for (int r = 0; r < 5; ++r) {
    const auto t0 = Clock::now();
    std::memcpy(b.data(), a.data(), n);
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    best = std::max(best, 2.0 * static_cast<double>(n) / s / 1e9);
    std::swap(a, b);
  }
  return best;
}

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

// UpdParams::fast_exact_band at the PCL peer's settings.
constexpr double kExactBand = 0.02;

// The pipeline parameters of the PCL peer's settings, on our side.
PipelineParams pclSettings(const Eigen::Vector3f& up, double voxel_m, double normal_radius_m,
                           double d_m) {
  PipelineParams p;
  p.up = up;
  p.preprocess.disableAll();
  p.preprocess.voxel_enabled = voxel_m > 0;
  p.preprocess.voxel_m = voxel_m > 0 ? voxel_m : 0.02;
  p.normals.radius_m = normal_radius_m;
  p.upd.radius_m = d_m;
  // The points within kExactBand of zeta_min get the exact sums (as config/lidar.ini and
  // config/tractor-stereo.ini): cheap on these clouds, a few dozen points per lattice cell. The
  // sensor-rate frame pipeline leaves it off, as UpdParams does by default.
  p.upd.fast_exact_band = kExactBand;
  return p;
}

PeerSettings peerOf(const PipelineParams& p) {
  PeerSettings s;
  s.voxel_enabled = p.preprocess.voxel_enabled;
  s.voxel_m = p.preprocess.voxel_m;
  s.normal_radius_m = p.normals.radius_m;
  s.upd_radius_m = p.upd.radius_m;
  s.min_neighbors = p.upd.min_neighbors;
  s.up = p.unitUp();
  s.vertical_band_rad = p.normals.vertical_band_rad;
  return s;
}

// Neighbour visits the peer's UPD search would make: its cost, to decide whether to run it.
double peerCostEstimate(const PointCloud& cloud, const PipelineParams& p) {
  const PointCloud pre = preprocess(cloud, p.preprocess);
  if (pre.empty()) return 0;
  const KdTree tree(pre);
  std::vector<std::uint32_t> nb;
  double sum = 0;
  const std::size_t step = std::max<std::size_t>(1, pre.size() / 64);
  std::size_t samples = 0;
  for (std::size_t i = 0; i < pre.size(); i += step) {
    if (!pre.isFinite(i)) continue;
    tree.radiusSearch(pre.point(i), static_cast<float>(p.upd.radius_m), nb);
    sum += static_cast<double>(nb.size());
    ++samples;
  }
  return samples ? sum / static_cast<double>(samples) * static_cast<double>(pre.size()) : 0;
}

// ---------------------------------------------------------------------------------------------
// The report.

class Report {
 public:
  json root = json::object();
  std::vector<Target> targets;

  void target(const std::string& name, double value, double limit, bool upper,
              const std::string& unit) {
    targets.push_back({name, value, limit, upper, unit});
  }
};

void printRule() { std::printf("%s\n", std::string(100, '-').c_str()); }

// A case with our fast path, our exact path and the PCL peer at identical settings.
json peerCase(const std::string& name, const std::string& source, const PointCloud& cloud,
              const PipelineParams& params, const Options& o, int repeats, Report& report,
              bool count_for_speedup_target) {
  json c = {{"name", name},
            {"source", source},
            {"points_in", cloud.size()},
            {"fast_exact_band", params.upd.fast_exact_band}};
  omp_set_num_threads(1);
  PipelineParams fast = params;
  fast.upd.method = UpdMethod::Fast;
  PipelineResult fr;
  const double ours = timeMedian([&] { fr = runPipeline(cloud, fast); }, repeats);
  c["points_scored"] = fr.cloud.size();
  c["ours_fast_ms"] = num(ours);
  c["ours_fast_stages"] = {{"preprocess_ms", fr.timings.preprocess_ms},
                           {"normals_ms", fr.timings.normals_ms},
                           {"upd_ms", fr.timings.upd_ms},
                           {"classify_ms", fr.timings.classify_ms}};
  // Our exact path, once, single core like the peer.
  PipelineParams exact = params;
  exact.upd.method = UpdMethod::Exact;
  double ours_exact = kNaN;
  const double exact_cost = peerCostEstimate(cloud, params);
  const bool run_exact_full = exact_cost < (o.quick ? 3e8 : 3e9);
  if (run_exact_full) {
    const auto t0 = Clock::now();
    const PipelineResult er = runPipeline(cloud, exact);
    ours_exact = msSince(t0);
  }
  c["ours_exact_ms"] = num(ours_exact);
  c["exact_neighbour_visits"] = exact_cost;
  // Agreement with exact on the same pre-processed cloud (two threads: it is not timed).
  omp_set_num_threads(2);
  const ExactReference ref = exactReference(fr.cloud, params, o.quick ? 3000 : 20000);
  const Agreement a = agreement(ref, fr.upd, params);
  c["agreement"] = a.toJson();
  report.target(name + ": mean |dzeta| fast vs exact", a.mean_abs_dzeta, kMaxMeanDzeta, true, "");
  report.target(name + ": same label fast vs exact", a.same_label, kMinSameLabel, false, "");
  // The PCL peer, once.
  omp_set_num_threads(1);
  double pcl_ms = kNaN;
  if (o.quick) {
    c["pcl"] = {{"skipped", "--quick"}};
  } else if (exact_cost > 6e9) {
    c["pcl"] = {{"skipped", "estimated " +
                                std::to_string(static_cast<long long>(exact_cost / 1e9)) +
                                "e9 neighbour visits (minutes)"}};
  } else {
    const PeerResult peer = runPclPipeline(cloud, peerOf(params));
    pcl_ms = peer.total_ms;
    c["pcl"] = {{"total_ms", peer.total_ms},
                {"voxel_ms", peer.voxel_ms},
                {"normals_ms", peer.normals_ms},
                {"upd_ms", peer.upd_ms},
                {"points_scored", peer.cloud.size()}};
  }
  c["ratio_pcl_over_ours"] = num(pcl_ms / ours);
  c["ratio_ours_exact_over_fast"] = num(ours_exact / ours);
  if (count_for_speedup_target && std::isfinite(pcl_ms)) {
    report.target(name + ": PCL pipeline / ours", pcl_ms / ours, kMinSpeedupVsPcl, false, "x");
  }
  std::printf(
      "%-34s %8zu pts  ours %9.2f ms  exact %9.1f ms  PCL %9.1f ms  PCL/ours %7.1fx  "
      "|dz| %.4f  labels %.2f%%%s\n",
      name.c_str(), fr.cloud.size(), ours, ours_exact, pcl_ms, pcl_ms / ours, a.mean_abs_dzeta,
      100 * a.same_label,
      a.compared < a.finite ? (" (" + std::to_string(a.compared) + " sampled)").c_str() : "");
  std::fflush(stdout);
  return c;
}

// The targets table and the JSON file.
int finish(Report& report, const Options& o, double bandwidth) {
  json& root = report.root;
  // The memory-bandwidth floor of a frame: read x, y, z once, write the per-pixel results once
  // (normal 12 B, curvature 4, r 12, zeta 4, k 4, label 1, cost 4, slope 4 = 45 B).
  const double floor_bytes = 307200.0 * (12 + 45);
  root["bandwidth_floor"] = {{"bytes_per_frame", floor_bytes},
                             {"copy_bandwidth_GBps", bandwidth},
                             {"floor_ms", floor_bytes / (bandwidth * 1e9) * 1e3}};

  // ------------------------------------------------------------------ Targets.
  printRule();
  std::printf("Targets (issue 5)\n");
  printRule();
  json tj = json::array();
  std::size_t met = 0;
  for (const Target& t : report.targets) {
    std::printf("  [%s] %-62s %10.4g %s %-6g %s\n", t.met() ? " met  " : "NOT MET", t.name.c_str(),
                t.value, t.upper_bound ? "<=" : ">=", t.limit, t.unit.c_str());
    tj.push_back({{"name", t.name},
                  {"value", num(t.value)},
                  {"limit", t.limit},
                  {"bound", t.upper_bound ? "<=" : ">="},
                  {"unit", t.unit},
                  {"met", t.met()}});
    met += t.met() ? 1 : 0;
  }
  std::printf("%zu of %zu targets met; memory-bandwidth floor of a frame %.2f ms\n", met,
              report.targets.size(), floor_bytes / (bandwidth * 1e9) * 1e3);
  root["targets"] = tj;
  root["targets_met"] = met;
  root["targets_total"] = report.targets.size();
  if (!o.json_path.empty()) {
    std::ofstream out(o.json_path);
    if (!out) throw std::runtime_error("cannot write " + o.json_path);
    out << root.dump(2) << "\n";
    if (!out) throw std::runtime_error("error writing " + o.json_path);
    std::printf("report written to %s\n", o.json_path.c_str());
  }
  return 0;
}

int run(const Options& o) {
  Report report;
  json& root = report.root;
  std::printf("upd_bench: data from %s%s\n", o.data_dir.c_str(), o.quick ? " (--quick)" : "");
  const double bandwidth = copyBandwidthGBs();
  // The OpenMP wait policy changes the two-core timings: threads woken from sleep for each
  // parallel region (passive) cost more than threads that spin a while first (the default).
  const char* policy_env = std::getenv("OMP_WAIT_POLICY");
  const std::string policy = policy_env && *policy_env ? policy_env : "default";
  root["machine"] = {{"cpu", cpuModel()},
                     {"logical_cpus", omp_get_num_procs()},
                     {"copy_bandwidth_GBps", bandwidth},
                     {"compiler", __VERSION__},
                     {"omp_wait_policy", policy}};
  std::printf("machine: %s, %d logical CPUs, copy bandwidth %.1f GB/s, OMP_WAIT_POLICY %s\n",
              cpuModel().c_str(), omp_get_num_procs(), bandwidth, policy.c_str());
  root["map_stage"] = MapStage::kind();

  // ------------------------------------------------------------------ Kinect frames.
  std::vector<Frame> frames;
  frames.push_back(pcdFrame(o, "office1", "pcl/office1.pcd", {0.f, -1.f, 0.01f}));
  frames.push_back(pcdFrame(o, "region_growing_rgb_tutorial",
                            "pcl-data/region_growing_rgb_tutorial.pcd", {0.06f, -0.85f, -0.53f}));
  frames.push_back(generatedFrame());

  printRule();
  std::printf(
      "Frame pipeline, organized 640 x 480, every pixel scored: depth image / organized "
      "cloud -> normals (0.05 m) -> UPD (d_m 0.5 m) -> labels -> map update\n");
  std::printf("map update: %s\n", MapStage::kind());
  printRule();
  json frame_cases = json::array();
  std::vector<PipelineResult> frame_results(frames.size());
  std::vector<double> one_core(frames.size(), kNaN);
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const Frame& fr = frames[f];
    json c = {{"name", fr.name}, {"source", fr.source}};
    if (!fr.available) {
      c["skipped"] = fr.skip_reason;
      std::printf("%-30s skipped: %s\n", fr.name.c_str(), fr.skip_reason.c_str());
      frame_cases.push_back(c);
      continue;
    }
    PipelineParams p;
    p.up = fr.up;
    p.preprocess.disableAll();  // keep the image: every pixel is scored
    p.normals.radius_m = 0.05;
    p.upd.radius_m = 0.5;
    const auto [t1, t2] = timeOneAndTwoCores(fr, p, o.repeats, &frame_results[f]);
    one_core[f] = t1.total_ms;
    c["points"] = t1.points;
    c["points_scored"] = t1.scored;
    c["starts_from"] = fr.depth ? "depth image" : "organized cloud (PCD)";
    c["one_core_ms"] = num(t1.total_ms);
    c["one_core_stages"] = t1.stages;
    c["two_core_ms"] = num(t2.total_ms);
    c["two_core_stages"] = t2.stages;
    c["two_core_speedup"] = num(t1.total_ms / t2.total_ms);
    c["normals_method"] = frame_results[f].organized_normals ? "image-window scans" : "hash grid";
    // UpdParams::fast_cells_per_point: the lattice's cells per d_m on this frame.
    c["lattice_cells_per_radius"] = frame_results[f].fast_cells_per_radius;
    report.target(fr.name + ": frame pipeline, one core (median)", t1.total_ms, kFrameBudgetMs,
                  true, "ms");
    report.target(fr.name + ": second core speedup", t1.total_ms / t2.total_ms, kMinTwoCoreSpeedup,
                  false, "x");
    std::printf(
        "%-30s %7zu px %7zu scored  one core %7.2f ms  two cores %7.2f ms (x%.2f)  "
        "[normals %.2f, UPD %.2f, labels %.2f, map %.2f ms]\n",
        fr.name.c_str(), t1.points, t1.scored, t1.total_ms, t2.total_ms, t1.total_ms / t2.total_ms,
        t1.stages["normals_ms"].get<double>(), t1.stages["upd_ms"].get<double>(),
        t1.stages["classify_ms"].get<double>(), t1.stages["map_update_ms"].get<double>());
    std::fflush(stdout);
    frame_cases.push_back(c);
  }
  const double peak_mb = peakRssMb();
  root["frame_pipeline_peak_rss_mb"] = peak_mb;
  report.target("peak memory after the 640 x 480 frame pipelines (whole process)", peak_mb,
                kMaxPeakMemoryMb, true, "MB");
  std::printf("peak resident memory so far (the frames loaded and scored): %.0f MB\n", peak_mb);
  if (o.frames_only) {
    root["frames"] = frame_cases;
    return finish(report, o, bandwidth);
  }

  // Agreement of the frame pipeline with the exact path at full resolution.
  printRule();
  std::printf(
      "Agreement of the frame pipeline with the exact path (same cloud, full "
      "resolution; exact UPD on evenly spaced samples)\n");
  printRule();
  for (std::size_t f = 0; f < frames.size(); ++f) {
    if (!frames[f].available) continue;
    PipelineParams p;
    p.up = frames[f].up;
    p.preprocess.disableAll();
    p.normals.radius_m = 0.05;
    p.upd.radius_m = 0.5;
    omp_set_num_threads(2);
    const ExactReference ref = exactReference(frame_results[f].cloud, p, o.quick ? 2000 : 12000);
    const Agreement a = agreement(ref, frame_results[f].upd, p);
    frame_cases[f]["agreement"] = a.toJson();
    report.target(frames[f].name + ": frame mean |dzeta| fast vs exact", a.mean_abs_dzeta,
                  kMaxMeanDzeta, true, "");
    report.target(frames[f].name + ": frame same label fast vs exact", a.same_label, kMinSameLabel,
                  false, "");
    std::printf(
        "%-30s %6zu of %6zu points compared: mean |dzeta| %.5f, max %.4f, same label "
        "%.3f%% (%d lattice cells per d_m; exact normals %.0f ms, exact UPD of the sample %.0f "
        "ms, 2 threads)\n",
        frames[f].name.c_str(), a.compared, a.finite, a.mean_abs_dzeta, a.max_abs_dzeta,
        100 * a.same_label, frame_results[f].fast_cells_per_radius, a.exact_normals_ms,
        a.exact_upd_ms);
    // What the labels' agreement costs at full resolution (not a target: the trade-off
    // docs/PERFORMANCE.md discusses): normals per 3 x 3 pixels and exact sums within 0.004 of
    // zeta_min.
    PipelineParams accurate = p;
    accurate.normals.fast_block_px = 3;
    accurate.upd.fast_exact_band = 0.004;
    omp_set_num_threads(1);
    PipelineResult ar;
    const FrameTiming at = timeFramePipeline(frames[f], accurate, std::max(3, o.repeats / 3), &ar);
    omp_set_num_threads(2);
    const Agreement aa = agreement(ref, ar.upd, accurate);
    frame_cases[f]["accuracy_settings"] = {{"fast_block_px", 3},
                                           {"fast_exact_band", 0.004},
                                           {"one_core_ms", num(at.total_ms)},
                                           {"agreement", aa.toJson()}};
    std::printf(
        "%-30s   with 3 x 3 px normals and exact sums within 0.004 of zeta_min: one core "
        "%.2f ms, mean |dzeta| %.5f, same label %.3f%%\n",
        "", at.total_ms, aa.mean_abs_dzeta, 100 * aa.same_label);
    std::fflush(stdout);
  }

  // Normals alone: ours against PCL's IntegralImageNormalEstimation.
  printRule();
  std::printf(
      "Normals alone, organized frames, one core: computeNormalsOrganized (r = 0.05 m) "
      "vs PCL IntegralImageNormalEstimation (COVARIANCE_MATRIX, smoothing 10 px)\n");
  printRule();
  json normal_cases = json::array();
  for (const Frame& fr : frames) {
    if (!fr.available) continue;
    omp_set_num_threads(1);
    NormalParams np;
    np.radius_m = 0.05;
    std::size_t valid = 0;
    const double ours = timeMedian(
        [&] { valid = fr.cloud.size() - computeNormalsOrganized(fr.cloud, np, fr.up).invalid; },
        o.repeats);
    std::vector<double> pcl_runs;
    std::size_t pcl_valid = 0;
    for (int r = 0; r < std::max(3, o.repeats / 3); ++r) {
      const IntegralPeerResult pr = runPclIntegralNormals(fr.cloud, 0.02f, 10.0f);
      pcl_runs.push_back(pr.ms);
      pcl_valid = pr.valid;
    }
    const double pcl = median(pcl_runs);
    normal_cases.push_back({{"name", fr.name},
                            {"ours_ms", num(ours)},
                            {"ours_valid", valid},
                            {"pcl_integral_ms", num(pcl)},
                            {"pcl_valid", pcl_valid},
                            {"ratio_pcl_over_ours", num(pcl / ours)}});
    std::printf("%-30s ours %7.2f ms (%zu normals)  PCL %7.2f ms (%zu normals)  PCL/ours %.1fx\n",
                fr.name.c_str(), ours, valid, pcl, pcl_valid, pcl / ours);
    std::fflush(stdout);
  }
  root["normals_alone"] = normal_cases;

  // ------------------------------------------------------------------ PCL settings.
  printRule();
  std::printf(
      "At the PCL peer's settings (one core; PCL run once): ours fast (exact sums within %.2f "
      "of zeta_min), ours exact, PCL pipeline; agreement of fast with exact\n",
      kExactBand);
  printRule();
  json peer_cases = json::array();
  for (const Frame& fr : frames) {
    if (!fr.available) {
      peer_cases.push_back({{"name", fr.name + " (voxel 0.02)"}, {"skipped", fr.skip_reason}});
      continue;
    }
    const PointCloud cloud = fr.depth ? depthToCloud(*fr.depth, fr.intrinsics) : fr.cloud;
    peer_cases.push_back(peerCase(fr.name + " voxel 0.02", fr.source, cloud,
                                  pclSettings(fr.up, 0.02, 0.05, 0.5), o, o.repeats, report, true));
  }
  // The outdoor LiDAR scan: the settings of config/lidar.ini (range 1-40 m, voxel 0.1 m,
  // normals 0.5 m, d_m 1.0 m, 6 lattice cells per d_m), identical on both sides.
  if (const auto path = dataFile(o, "fast_gicp/251370668.pcd")) {
    const PointCloud lidar = io::readCloud(*path);
    PipelineParams p = pclSettings(Eigen::Vector3f::UnitZ(), 0.1, 0.5, 1.0);
    p.preprocess.range_enabled = true;
    p.preprocess.range_min_m = 1.0;
    p.preprocess.range_max_m = 40.0;
    p.upd.min_neighbors = 3;
    p.upd.fast_cells_per_radius = 6;
    p.classify.zeta_min = 0.93;
    p.classify.zeta_caution = 0.98;
    p.classify.max_slope_rad = 20.0 * kDegToRad;
    p.classify.min_neighbors = 5;
    // The peer has no range filter of its own: it gets the cut cloud.
    PipelineParams cut = p;
    cut.preprocess.voxel_enabled = false;
    const PointCloud in_range = preprocess(lidar, cut.preprocess);
    PipelineParams rest = p;
    rest.preprocess.range_enabled = false;
    peer_cases.push_back(peerCase("lidar fast_gicp d_m 1.0",
                                  "../shared/data/fast_gicp/251370668.pcd "
                                  "(range 1-40 m applied first)",
                                  in_range, rest, o, o.repeats, report, false));
  } else {
    peer_cases.push_back(
        {{"name", "lidar fast_gicp d_m 1.0"}, {"skipped", "fast_gicp/251370668.pcd not found"}});
    std::printf("lidar fast_gicp: skipped (file not found)\n");
  }
  // The paper's corner sampled every 0.01 m: no voxel grid, normals 0.05 m, d_m 0.5 m.
  {
    const Scene corner = makeScene("corner");
    peer_cases.push_back(peerCase("corner 0.01 m", "makeScene(\"corner\"), 0.01 m grid",
                                  corner.cloud, pclSettings(corner.up, 0, 0.05, 0.5), o, o.repeats,
                                  report, false));
  }
  root["pcl_settings"] = peer_cases;

  // ------------------------------------------------------------------ Growth with size.
  printRule();
  std::printf(
      "Growth with the number of points: 1 to 16 tiles of makeScene(\"rocks\") (0.02 m "
      "grid, 3 x 3 m each) side by side, no voxel grid, normals 0.05 m, d_m 0.5 m\n");
  printRule();
  json size_cases = json::array();
  double per_point_x1 = kNaN, per_point_x16 = kNaN;
  SceneParams tile_params;
  tile_params.spacing_m = 0.02;
  tile_params.noise_m = 0.002;
  const Scene tile = makeScene("rocks", tile_params);
  for (const int factor : {1, 2, 4, 8, 16}) {
    // Tiles on a 4-wide grid, 3.05 m apart (the tile is 3 m across): a bigger field of rocks
    // at the same density, so the work per point should stay the same.
    PointCloud field;
    field.reserve(tile.cloud.size() * static_cast<std::size_t>(factor));
    for (int t = 0; t < factor; ++t) {
      const float dx = 3.05f * static_cast<float>(t % 4), dy = 3.05f * static_cast<float>(t / 4);
      for (std::size_t i = 0; i < tile.cloud.size(); ++i) {
        field.push_back(tile.cloud.x[i] + dx, tile.cloud.y[i] + dy, tile.cloud.z[i]);
      }
    }
    field.sensor_origin = tile.cloud.sensor_origin;
    const int reps = std::max(3, o.repeats / factor);
    json c = peerCase("rocks x" + std::to_string(factor),
                      std::to_string(factor) + " tiles of makeScene(\"rocks\"), 0.02 m grid", field,
                      pclSettings(tile.up, 0, 0.05, 0.5), o, reps, report, false);
    const double per_point = c["ours_fast_ms"].get<double>() / static_cast<double>(field.size());
    c["ours_ns_per_point"] = per_point * 1e6;
    if (factor == 1) per_point_x1 = per_point;
    if (factor == 16) per_point_x16 = per_point;
    size_cases.push_back(c);
  }
  root["growth_with_size"] = size_cases;
  report.target("time per point, x16 / x1 (linear growth)", per_point_x16 / per_point_x1,
                kMaxPerPointGrowth, true, "x");

  // ------------------------------------------------------------------ Growth with d_m.
  printRule();
  std::printf("Growth with d_m: the generated Kinect frame, frame pipeline on one core\n");
  printRule();
  json dm_cases = json::array();
  double t_small = kNaN, t_large = kNaN;
  const Frame& gen = frames.back();
  for (const double dm : {0.25, 0.5, 1.0, 2.0}) {
    PipelineParams p;
    p.up = gen.up;
    p.preprocess.disableAll();
    p.normals.radius_m = 0.05;
    p.upd.radius_m = dm;
    omp_set_num_threads(1);
    PipelineResult r;
    const FrameTiming t = timeFramePipeline(gen, p, o.repeats, &r);
    omp_set_num_threads(2);
    const ExactReference ref = exactReference(r.cloud, p, o.quick ? 1000 : (dm > 1 ? 3000 : 6000));
    const Agreement a = agreement(ref, r.upd, p);
    json c = {{"d_m", dm},
              {"one_core_ms", num(t.total_ms)},
              {"stages", t.stages},
              {"agreement", a.toJson()}};
    // The peer at its settings on this frame, when it takes less than a few minutes.
    const PipelineParams ps = pclSettings(gen.up, 0.02, 0.05, dm);
    const double cost = peerCostEstimate(r.cloud, ps);
    double pcl_ms = kNaN;
    if (o.quick) {
      c["pcl"] = {{"skipped", "--quick"}};
    } else if (cost > 6e9) {
      c["pcl"] = {{"skipped", "estimated neighbour visits " + std::to_string(cost)}};
    } else {
      omp_set_num_threads(1);
      pcl_ms = runPclPipeline(r.cloud, peerOf(ps)).total_ms;
      c["pcl"] = {{"total_ms", pcl_ms}, {"settings", "voxel 0.02, normals 0.05"}};
    }
    c["ratio_pcl_over_ours"] = num(pcl_ms / t.total_ms);
    if (dm == 0.25) t_small = t.total_ms;
    if (dm == 2.0) t_large = t.total_ms;
    report.target(
        "generated frame d_m " + std::to_string(dm).substr(0, 4) + ": mean |dzeta| fast vs exact",
        a.mean_abs_dzeta, kMaxMeanDzeta, true, "");
    report.target(
        "generated frame d_m " + std::to_string(dm).substr(0, 4) + ": same label fast vs exact",
        a.same_label, kMinSameLabel, false, "");
    std::printf(
        "d_m %.2f m: one core %7.2f ms [UPD %.2f ms]  PCL %9.1f ms  PCL/ours %7.1fx  "
        "|dz| %.4f  labels %.2f%% (%zu sampled)\n",
        dm, t.total_ms, t.stages["upd_ms"].get<double>(), pcl_ms, pcl_ms / t.total_ms,
        a.mean_abs_dzeta, 100 * a.same_label, a.compared);
    std::fflush(stdout);
    dm_cases.push_back(c);
  }
  root["growth_with_radius"] = dm_cases;
  report.target("time at d_m 2 m / time at d_m 0.25 m", t_large / t_small, kMaxDmRatio, true, "x");

  root["frames"] = frame_cases;
  return finish(report, o, bandwidth);
}

}  // namespace
}  // namespace upd::bench

int main(int argc, char** argv) {
  upd::bench::Options o;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      const auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
        return argv[++i];
      };
      if (a == "--data") {
        o.data_dir = value();
      } else if (a == "--json") {
        o.json_path = value();
      } else if (a == "--quick") {
        o.quick = true;
      } else if (a == "--frames-only") {
        o.frames_only = true;
      } else if (a == "--repeats") {
        o.repeats = std::stoi(value());
        if (o.repeats < 1) throw std::invalid_argument("--repeats must be >= 1");
      } else if (a == "--help" || a == "-h") {
        std::printf(
            "usage: upd_bench [--data DIR] [--json OUT.json] [--quick] [--frames-only] "
            "[--repeats N]\n");
        return 0;
      } else {
        throw std::invalid_argument("unknown option " + a + " (see --help)");
      }
    }
    return upd::bench::run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "upd_bench: %s\n", e.what());
    return 1;
  }
}
