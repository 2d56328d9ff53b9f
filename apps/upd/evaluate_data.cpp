// The labelled clouds of `upd evaluate` and `upd train` (evaluate_data.h).
#include "evaluate_data.h"

#include "depth_input.h"

#include "upd/core/camera.h"
#include "upd/io/class_map.h"
#include "upd/io/cloud_io.h"
#include "upd/io/kitti_bin.h"
#include "upd/sim/render.h"
#include "upd/sim/robot.h"
#include "upd/sim/scenes.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <stdexcept>

namespace upd::app {

namespace fs = std::filesystem;

namespace {

// Scenes and worlds of the test split; the others train the shipped classifier.
const std::set<std::string> kHeldOutScenes = {"stairs", "ditch", "corner",
                                              "world ramp", "world ditch", "world trapped"};
const char* const kSceneNames[] = {"ramp", "stairs", "step", "ditch", "rocks", "corner"};
const char* const kWorldNames[] = {"mixed", "ramp", "rocks", "ditch", "corridor", "trapped"};
constexpr double kSceneNoise_m = 0.005;

void visitScenes(const std::function<void(LabelledCloud&)>& visit) {
  for (double noise : {0.0, kSceneNoise_m}) {
    for (const char* name : kSceneNames) {
      sim::SceneParams p;
      p.spacing_m = 0.02;
      p.noise_m = noise;
      sim::Scene s = sim::makeScene(name, p);
      LabelledCloud c;
      c.name = std::string("scene ") + name;
      c.group = noise > 0 ? "generated scenes, 5 mm noise" : "generated scenes";
      c.scene = name;
      c.held_out = kHeldOutScenes.count(name) > 0;
      c.trains_shipped_model = !c.held_out;
      c.config = "dune-kinect.ini";
      c.cloud = std::move(s.cloud);
      c.truth = std::move(s.truth);
      c.up = s.up;
      visit(c);
    }
  }
}

// Three views of the rover's Kinect along the way from a world's start to its goal.
void visitWorldViews(const std::function<void(LabelledCloud&)>& visit) {
  sim::CameraMountParams mount;
  mount.image_downscale = 4;
  const core::CameraIntrinsics K = sim::simulatedIntrinsics(mount);
  for (bool noisy : {false, true}) {
    sim::DepthNoise noise;
    if (!noisy) {
      noise.sigma_coeff_per_m = 0;
      noise.quantize_mm = false;
    }
    for (const char* name : kWorldNames) {
      const sim::WorldSpec w = sim::makeWorld(name);
      const Eigen::Vector2d start = w.start_xy_yaw.head<2>(), to_goal = w.goal_xy - start;
      const double yaw = std::atan2(to_goal.y(), to_goal.x());
      for (int v = 0; v < 3; ++v) {
        const Eigen::Vector2d xy = start + (0.05 + 0.25 * v) * to_goal;
        const Eigen::Isometry3d pose =
            sim::bodyPoseFlat({xy.x(), xy.y(), yaw + 0.3 * (v - 1)}) * sim::cameraOnRobot(mount);
        sim::RenderedScene r = sim::renderScene(w.terrain, pose, K, noise, 11 + v);
        LabelledCloud c;
        c.name = std::string("world ") + name + " view " + std::to_string(v + 1);
        c.group = noisy ? "simulated Kinect, noise" : "simulated Kinect, no noise";
        c.scene = std::string("world ") + name;
        c.held_out = kHeldOutScenes.count(c.scene) > 0;
        c.trains_shipped_model = !c.held_out;
        c.config = "dune-kinect.ini";
        c.cloud = std::move(r.scene.cloud);
        c.truth = std::move(r.scene.truth);
        c.up = r.scene.up;
        visit(c);
      }
    }
  }
}

struct RealFrame {
  const char* path;      // under the shared data folder
  const char* calib;     // depth PNG: its calibration; else nullptr
  Eigen::Vector3d up;    // roughly up in the frame (SOURCES.md)
};

const RealFrame kRealFrames[] = {
    {"pcl/office1.pcd", nullptr, {0, -1, 0}},
    {"pcl-data/region_growing_rgb_tutorial.pcd", nullptr, {0.06, -0.85, -0.53}},
    {"pcl/table_scene_mug_stereo_textured.pcd", nullptr, {0.02, -0.84, -0.55}},
    {"rtabmap/rgbd/depth/17.png", "rtabmap/rgbd/calib/17.yaml", {0, -1, 0}},
};

// The cloud in the camera-optical frame (a depth PNG is not moved by its local_transform:
// the floor is found below the camera).
core::PointCloud readCameraFrame(const fs::path& dir, const RealFrame& f) {
  if (!f.calib) return io::readCloud((dir / f.path).string());
  const auto calib = mrpt_bridge::loadDepthCalibration((dir / f.calib).string());
  return core::depthToCloud(depthImageOf((dir / f.path).string(), calib, 0.001), calib.K);
}

void visitRealFrames(const DataOptions& o, const std::function<void(LabelledCloud&)>& visit,
                     std::vector<std::string>& notes) {
  const fs::path dir = o.shared_dir;
  for (const RealFrame& f : kRealFrames) {
    if (!fs::exists(dir / f.path)) {
      notes.push_back(std::string(f.path) + ": not in " + o.shared_dir + ", skipped");
      continue;
    }
    LabelledCloud c;
    c.cloud = readCameraFrame(dir, f);
    const core::FloorPlane plane = core::fitFloorPlane({&c.cloud}, core::FloorPlaneParams{}, f.up.normalized());
    if (!plane.found) {
      notes.push_back(std::string(f.path) + ": no floor found (" + plane.failure + "), skipped");
      continue;
    }
    c.name = f.path;
    c.group = "real RGB-D frames, geometric labels";
    c.scene = f.path;
    c.config = "dune-kinect.ini";
    c.up = plane.normal.cast<float>();
    c.truth = core::labelByFloor(c.cloud, plane, o.geometric);
    visit(c);
  }
}

// The scans of a semantic folder (SemanticKITTI: velodyne/ + labels/; RELLIS-3D:
// os1_cloud_node_kitti_bin/ + os1_cloud_node_semantickitti_label_id/; or both in one folder).
std::vector<std::pair<fs::path, fs::path>> scansOf(const fs::path& input) {
  std::vector<std::pair<fs::path, fs::path>> out;
  if (fs::is_regular_file(input)) {
    out.emplace_back(input, fs::path(input).replace_extension(".label"));
    if (!fs::exists(out.back().second)) {
      out.back().second = input.parent_path().parent_path() / "labels" / input.stem();
      out.back().second += ".label";
    }
    return out;
  }
  if (!fs::is_directory(input)) throw std::runtime_error("'" + input.string() + "': no such file or folder");
  fs::path bins = input, labels = input;
  for (const auto& [b, l] : {std::pair<const char*, const char*>{"velodyne", "labels"},
                             {"os1_cloud_node_kitti_bin", "os1_cloud_node_semantickitti_label_id"}}) {
    if (fs::is_directory(input / b)) {
      bins = input / b;
      labels = input / l;
    }
  }
  for (const auto& e : fs::directory_iterator(bins)) {
    if (e.path().extension() != ".bin") continue;
    out.emplace_back(e.path(), labels / e.path().stem());
    out.back().second += ".label";
  }
  std::sort(out.begin(), out.end());
  if (out.empty()) throw std::runtime_error("'" + input.string() + "': no .bin scan in it");
  return out;
}

void visitSemantic(const DataOptions& o, const std::function<void(LabelledCloud&)>& visit,
                   std::vector<std::string>& notes) {
  if (o.class_map.empty()) {
    throw std::invalid_argument("semantic LiDAR inputs need --class-map FILE (share/class_maps/)");
  }
  const io::ClassMap map = io::readClassMap(o.class_map);
  for (std::size_t s = 0; s < o.semantic_inputs.size(); ++s) {
    const auto scans = scansOf(o.semantic_inputs[s]);
    const std::size_t n = std::min<std::size_t>(scans.size(), std::max(1, o.max_scans));
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = k * scans.size() / n;
      LabelledCloud c;
      c.cloud = io::readKittiBin(scans[i].first.string()).cloud;
      const auto labels = io::readSemanticKittiLabels(scans[i].second.string(), c.cloud.size());
      c.truth = io::truthFromLabels(labels, map, scans[i].second.string());
      c.name = scans[i].first.string();
      c.group = "semantic LiDAR (" + fs::path(o.class_map).stem().string() + ")";
      // One input: its first two thirds train, the last third tests; several: every third.
      c.scene = o.semantic_inputs.size() > 1 ? o.semantic_inputs[s] : std::to_string(3 * k / n);
      c.held_out = o.semantic_inputs.size() > 1 ? s % 3 == 2 : 3 * k / n == 2;
      c.config = "lidar.ini";
      visit(c);
    }
    notes.push_back(o.semantic_inputs[s] + ": " + std::to_string(n) + " of " +
                    std::to_string(scans.size()) + " scans");
  }
}

}  // namespace

std::string findSharedDataDir() {
  if (const char* env = std::getenv("UPD_SHARED_DATA_DIR")) return fs::is_directory(env) ? env : "";
  for (const char* d : {"../shared/data", "/work/shared/data"}) {
    if (fs::is_directory(d)) return d;
  }
  return "";
}

void forEachLabelledCloud(const DataOptions& o, const std::function<void(LabelledCloud&)>& visit,
                          std::vector<std::string>& notes) {
  if (o.generated) {
    visitScenes(visit);
    visitWorldViews(visit);
  }
  if (!o.shared_dir.empty()) visitRealFrames(o, visit, notes);
  if (!o.semantic_inputs.empty()) visitSemantic(o, visit, notes);
}

}  // namespace upd::app
