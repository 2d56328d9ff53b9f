#include "frames.h"

#include <omp.h>
#include <sched.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>

#include "upd/sim/render.h"
#include "upd/core/stopwatch.h"
#include "upd/sim/terrain.h"
#include "upd/io/cloud_io.h"

#ifdef UPD_BENCH_HAVE_DEPTH_FILES
#include "upd/mrpt_bridge/depth_files.h"
#endif

#ifdef UPD_BENCH_HAVE_MAPS
#include "upd/maps/grid_fusion.h"
#include "upd/maps/traversability_grid.h"

namespace core = upd::core;
#endif

namespace upd::bench {

using namespace upd::sim;  // generated worlds, scenes and the depth renderer

namespace {

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
  void update(const core::PipelineResult& r, double time_s) {
    // Into the world frame (upd::transformCloud: vectorized, into the buffers of the last frame).
    core::transformCloud(r.cloud, pose_.cast<double>(), world_);
    const Eigen::Vector3f t = pose_.translation();
#ifdef UPD_BENCH_HAVE_MAPS
    maps::integrateScan(*grid_, maps::viewPoints(world_, r.classes, &r.upd),
                        Eigen::Vector2d(t.x(), t.y()), time_s, fusion_);
#else
    (void)time_s;
    constexpr int kSide = 400;
    counts_.assign(2 * kSide * kSide, 0);
    for (std::size_t i = 0; i < world_.size(); ++i) {
      const core::Label l = r.classes.label[i];
      if (l == core::Label::Unknown) continue;
      const int cx = static_cast<int>(std::floor((world_.x[i] - t.x()) / 0.05f)) + kSide / 2;
      const int cy = static_cast<int>(std::floor((world_.y[i] - t.y()) / 0.05f)) + kSide / 2;
      if (cx < 0 || cy < 0 || cx >= kSide || cy >= kSide) continue;
      ++counts_[2 * (cy * kSide + cx) + (l == core::Label::NonTraversable ? 1 : 0)];
    }
#endif
  }

 private:
  Eigen::Isometry3f pose_;
  core::PointCloud world_;
#ifdef UPD_BENCH_HAVE_MAPS
  std::optional<maps::TraversabilityGrid> grid_;
  maps::FusionParams fusion_;
#else
  std::vector<std::uint32_t> counts_;
#endif
};

// The frame pipeline: depth image (when there is one) -> cloud -> runPipeline -> map update.
// One loop keeps its cloud, result and map from frame to frame, as a sensor loop does: once
// warm, a frame allocates nothing.
class FrameLoop {
 public:
  FrameLoop(const Frame& f, const core::PipelineParams& params)
      : f_(f), params_(params), map_(f.pose_world_cloud) {}

  // One frame; its timings are kept when record.
  void run(bool record) {
    const core::Stopwatch frame;
    const core::PointCloud* input = &f_.cloud;
    if (f_.depth) {
      core::depthToCloud(*f_.depth, f_.intrinsics, converted_);
      input = &converted_;
    }
    const double t_convert = frame.elapsedMs();
    core::runPipeline(*input, params_, r_);
    const core::Stopwatch map;
    map_.update(r_, 0.1 * static_cast<double>(++frames_));
    const double map_time = map.elapsedMs();
    const double t_total = frame.elapsedMs();
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
  core::PipelineResult& result() { return r_; }

 private:
  const Frame& f_;
  core::PipelineParams params_;
  MapStage map_;
  core::PipelineResult r_;
  core::PointCloud converted_;
  int frames_ = 0;
  std::vector<double> total_, convert_, pre_, normals_, upd_, classify_, map_ms_;
};

// Keeps the calling thread on the CPU it runs on, for the one-core frames, and lets it go
// again. Unpinned, the scheduler moves it between a VM's vCPUs after the two-core frames, and
// the one-core median rises by 20-30 % (cold caches, idle vCPUs waking up); pinned, one core
// is one core.
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

}  // namespace

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

core::PointCloud inputCloud(const Frame& f) {
  return f.depth ? core::depthToCloud(*f.depth, f.intrinsics) : f.cloud;
}

std::vector<Frame> kinectFrames(const Options& o) {
  std::vector<Frame> frames;
  frames.push_back(pcdFrame(o, "office1", "pcl/office1.pcd", {0.f, -1.f, 0.01f}));
  frames.push_back(pcdFrame(o, "region_growing_rgb_tutorial",
                            "pcl-data/region_growing_rgb_tutorial.pcd", {0.06f, -0.85f, -0.53f}));
  frames.push_back(generatedFrame());
  for (const std::string& path : o.frames) {
    frames.push_back(userFrame(o, path));
    // (A name met before, as office1 given again, is numbered: each target keeps its own line.)
    Frame& added = frames.back();
    const auto taken = [&](const std::string& name) {
      return std::any_of(frames.begin(), frames.end() - 1,
                         [&](const Frame& f) { return f.name == name; });
    };
    const std::string stem = added.name;
    for (int n = 2; taken(added.name); ++n) added.name = stem + "#" + std::to_string(n);
  }
  return frames;
}

bool isDepthPng(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".png";
}

Frame userFrame(const Options& o, const std::string& path) {
  Frame f;
  f.name = std::filesystem::path(path).stem().string();
  f.source = path;
  f.up = Eigen::Vector3f(o.up[0], o.up[1], o.up[2]).normalized();
  if (isDepthPng(path)) {
#ifdef UPD_BENCH_HAVE_DEPTH_FILES
    core::DepthImage depth = mrpt_bridge::readDepthPng(path, o.depth_scale);
    if (!o.intrinsics.empty()) {
      const auto calibration = mrpt_bridge::loadDepthCalibration(o.intrinsics);
      f.intrinsics = calibration.K;
      if (calibration.camera_on_robot && !o.up_given) {  // (the robot's z in the camera frame)
        f.up = (calibration.camera_on_robot->linear().transpose() * Eigen::Vector3d::UnitZ())
                   .cast<float>()
                   .normalized();
      }
      if (f.intrinsics.width != depth.width || f.intrinsics.height != depth.height) {
        throw std::runtime_error(path + ": " + std::to_string(depth.width) + " x " +
                                 std::to_string(depth.height) + " pixels, where " +
                                 o.intrinsics + " is for " + std::to_string(f.intrinsics.width) +
                                 " x " + std::to_string(f.intrinsics.height));
      }
    } else {  // (the Kinect's focal length, the centre of the image)
      f.intrinsics.width = depth.width, f.intrinsics.height = depth.height;
      f.intrinsics.cx = (depth.width - 1) / 2.0, f.intrinsics.cy = (depth.height - 1) / 2.0;
    }
    f.cloud = core::depthToCloud(depth, f.intrinsics);
    f.depth = std::move(depth);
#else
    throw std::runtime_error(path + ": depth PNGs need libs/mrpt_bridge, which this build has not");
#endif
  } else {
    f.cloud = io::readCloud(path);
    if (!f.cloud.isOrganized()) {
      throw std::runtime_error(path + ": not an organized cloud (" +
                               std::to_string(f.cloud.size()) +
                               " points in one row): the frame tables take a camera's image");
    }
  }
  f.available = true;
  f.pose_world_cloud.linear() =
      Eigen::Quaternionf::FromTwoVectors(f.up, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  return f;
}

const char* mapStageKind() {
#ifdef UPD_BENCH_HAVE_MAPS
  return "upd::maps::integrateScan into a 20 x 20 m TraversabilityGrid of 0.05 m cells";
#else
  return "per-point binning into a 20 x 20 m grid of 0.05 m cells (libs/maps not built)";
#endif
}

FrameTiming timeFramePipeline(const Frame& f, const core::PipelineParams& params, int repeats,
                              core::PipelineResult* last) {
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

void oneAndTwoCoresInBlocks(int repeats, CoreProbe* probe, const std::function<void(bool)>& one,
                            const std::function<void(bool)>& two) {
  for (int timed = 0; timed < repeats; timed += kTimedInBlock) {
    const int n = std::min(kTimedInBlock, repeats - timed);
    if (probe) probe->sample();
    omp_set_num_threads(1);
    {
      const PinnedToThisCpu pin;
      for (int frame = -1; frame < n; ++frame) one(frame >= 0);
    }
    omp_set_num_threads(2);
    for (int frame = -1; frame < n; ++frame) two(frame >= 0);
  }
}

std::pair<FrameTiming, FrameTiming> timeOneAndTwoCores(const Frame& f, const core::PipelineParams& params,
                                                       int repeats, core::PipelineResult* last,
                                                       CoreProbe* probe) {
  FrameLoop one(f, params), two(f, params);
  oneAndTwoCoresInBlocks(
      repeats, probe, [&](bool record) { one.run(record); }, [&](bool record) { two.run(record); });
  std::pair<FrameTiming, FrameTiming> t{one.timing(), two.timing()};
  if (last) *last = std::move(one.result());
  return t;
}

double timeMedian(const std::function<void()>& f, int repeats) {
  std::vector<double> v;
  for (int run = -1; run < repeats; ++run) {
    const core::Stopwatch watch;
    f();
    if (run >= 0) v.push_back(watch.elapsedMs());
  }
  return median(v);
}

}  // namespace upd::bench
