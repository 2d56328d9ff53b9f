// Depth images on disk as a user has them: RTAB-Map's real depth PNG with its calibration YAML
// scores its floor as traversable; a TUM RGB-D folder (rendered by the simulator along a route,
// with groundtruth.txt) plays back into a map that matches the world's truth; bad folders stop
// with one line naming the file or field.
#include "run_upd.h"
#include "temp_dir.h"
#include "test_data.h"

#include "upd/core/pipeline.h"
#include "upd/mrpt_bridge/depth_files.h"
#include "upd/mrpt_bridge/ini_params.h"
#include "upd/mrpt_bridge/robot_config.h"
#include "upd/mrpt_bridge/simulated_run.h"
#include "upd/sim/render.h"
#include "upd/sim/robot.h"
#include "upd/sim/terrain.h"
#include "upd/sim/truth_raster.h"

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>

namespace upd {
namespace {

namespace fs = std::filesystem;
using test::CmdResult;
using test::runUpd;

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect.ini";

TEST(DepthPng, RealRtabmapFrameScoresItsFloorTraversable) {
  UPD_REQUIRE_SHARED_FILE(depth, "rtabmap/rgbd/depth/17.png");
  UPD_REQUIRE_SHARED_FILE(calib, "rtabmap/rgbd/calib/17.yaml");
  const CmdResult r = runUpd("analyze " + depth + " --intrinsics " + calib + " --config " + kConfig);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("307200 points in"), std::string::npos) << r.output;

  // The same steps in the library: the floor (z ~ 0 after local_transform) is traversable.
  const mrpt_bridge::DepthCalibration c = mrpt_bridge::loadDepthCalibration(calib);
  EXPECT_DOUBLE_EQ(c.K.fx, 525.0);
  EXPECT_DOUBLE_EQ(c.K.cy, 239.5);
  ASSERT_TRUE(c.camera_on_robot.has_value());
  EXPECT_NEAR(c.camera_on_robot->translation().z(), 0.429, 1e-3);
  const core::DepthImage d = mrpt_bridge::readDepthPng(depth);
  std::size_t valid = 0;
  for (float v : d.depth_m) valid += v > 0;
  EXPECT_EQ(valid, 232485u);  // as SOURCES.md counts them
  core::PipelineParams params;
  mrpt_bridge::IniReader ini(kConfig);
  mrpt_bridge::RobotConfigParts parts;
  parts.pipeline = &params;
  mrpt_bridge::readRobotConfig(ini, parts);
  const core::PipelineResult res =
      core::runPipeline(core::transformCloud(core::depthToCloud(d, c.K), *c.camera_on_robot), params);
  std::size_t floor = 0, floor_traversable = 0;
  for (std::size_t i = 0; i < res.cloud.size(); ++i) {
    if (!res.cloud.isFinite(i) || std::abs(res.cloud.z[i]) > 0.03 || res.cloud.x[i] > 3.5) continue;
    if (res.classes.label[i] == core::Label::Unknown) continue;
    ++floor;
    floor_traversable += res.classes.label[i] == core::Label::Traversable;
  }
  std::printf("rtabmap 17: %zu floor points within 3.5 m, %.3f traversable\n", floor,
              double(floor_traversable) / floor);
  ASSERT_GT(floor, 1000u);
  EXPECT_GT(double(floor_traversable) / floor, 0.8);
}

// A ROS camera_info YAML (no %YAML directive) of K.
void writeCameraInfo(const fs::path& path, const core::CameraIntrinsics& K) {
  std::ofstream(path) << "image_width: " << K.width << "\nimage_height: " << K.height
                      << "\ncamera_name: depth\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: ["
                      << K.fx << ", 0, " << K.cx << ", 0, " << K.fy << ", " << K.cy
                      << ", 0, 0, 1]\ndistortion_model: plumb_bob\n";
}

// A TUM folder of the simulated Dune driving through the mixed world: depth/*.png (5000 per m),
// depth.txt, groundtruth.txt (camera poses), calib.yaml and the world's truth grid.
std::size_t writeTumFolder(const fs::path& dir) {
  const sim::WorldSpec world = sim::makeWorld("mixed");
  mrpt_bridge::SimulationParams p;
  p.camera.image_downscale = 4;  // 160 x 120: the navigation loop's frames
  p.frame_spacing_m = 0.6;
  const auto route = mrpt_bridge::planSimulatedRoute(world, p);
  const core::CameraIntrinsics K = sim::simulatedIntrinsics(p.camera);
  fs::create_directories(dir / "depth");
  std::ofstream list(dir / "depth.txt"), gt(dir / "groundtruth.txt");
  list << "# depth maps\n# file: 'simulated'\n# timestamp filename\n" << std::fixed;
  gt << "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n" << std::fixed;
  for (std::size_t k = 0; k < route.size(); ++k) {
    const double t = 1305031102.0 + route[k].t_s;
    const Eigen::Isometry3d cam = route[k].pose_world_robot * sim::cameraOnRobot(p.camera);
    const core::DepthImage d = sim::renderDepth(world.terrain, cam, K, sim::DepthNoise{}, 7 + k);
    std::ostringstream name;
    name << std::fixed << std::setprecision(6) << t << ".png";
    mrpt_bridge::writeDepthPng((dir / "depth" / name.str()).string(), d, 1.0 / 5000);
    list << std::setprecision(6) << t << " depth/" << name.str() << "\n";
    const Eigen::Quaterniond q(cam.linear());
    const Eigen::Vector3d x = cam.translation();
    gt << std::setprecision(4) << t - 0.004 << std::setprecision(6) << " " << x.x() << " "
       << x.y() << " " << x.z() << " " << q.x() << " " << q.y() << " " << q.z() << " " << q.w()
       << "\n";
    gt << std::setprecision(4) << t + 0.006 << std::setprecision(6) << " " << x.x() << " "
       << x.y() << " " << x.z() << " " << q.x() << " " << q.y() << " " << q.z() << " " << q.w()
       << "\n";
  }
  writeCameraInfo(dir / "calib.yaml", K);
  mrpt_bridge::writeTruthMap(sim::TruthRaster(world.terrain, p.truth_cell_m),
                             (dir / "truth.yaml").string());
  return route.size();
}

TEST(PlaybackTum, SimulatedFolderMapsAsTheTruth) {
  const test::TempDir tmp("tum");
  const fs::path dir = tmp.path() / "rgbd_dataset_sim";
  const std::size_t frames = writeTumFolder(dir);
  const fs::path out = tmp.path() / "out";
  const std::string realtime = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect-realtime.ini";
  const CmdResult r = runUpd("playback " + dir.string() + " --intrinsics " +
                             (dir / "calib.yaml").string() + " --config " + realtime +
                             " --output " + out.string() + " --truth " +
                             (dir / "truth.yaml").string() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  std::printf("TUM folder, %zu frames: %s\n", frames, s["ground_truth"].dump().c_str());
  EXPECT_EQ(s["pose_source"], "ground truth");
  EXPECT_EQ(s["frames_read"].get<std::size_t>(), frames);
  EXPECT_EQ(s["frames_processed"].get<std::size_t>(), frames);
  EXPECT_GE(s["ground_truth"]["scores"]["precision"].get<double>(), 0.9);
  EXPECT_GE(s["ground_truth"]["scores"]["recall"].get<double>(), 0.9);
  EXPECT_TRUE(fs::exists(out / "sequence.rawlog"));
  EXPECT_TRUE(fs::exists(out / "map.png"));
}

// One line on stderr naming what is wrong, exit status 1.
void expectOneLineError(const CmdResult& r, const std::string& names) {
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(names), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

TEST(PlaybackTum, BadFoldersStopWithOneLine) {
  const test::TempDir tmp("tum-bad");
  const fs::path dir = tmp.path() / "seq";
  fs::create_directories(dir / "depth");
  std::ofstream(dir / "groundtruth.txt") << "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0 1\n";
  core::CameraIntrinsics K;
  K.width = 4;
  K.height = 3;
  writeCameraInfo(dir / "calib.yaml", K);
  const std::string cmd = "playback " + dir.string() + " --intrinsics " +
                          (dir / "calib.yaml").string() + " --config " + kConfig + " --output " +
                          (tmp.path() / "out").string() + " --quiet";
  expectOneLineError(runUpd(cmd), "depth.txt: not found");

  std::ofstream(dir / "depth.txt") << "1.0 depth/1.png\n1.5 depth/2.png\n";
  core::DepthImage d;
  d.width = 4;
  d.height = 3;
  d.depth_m.assign(12, 1.0f);
  mrpt_bridge::writeDepthPng((dir / "depth" / "1.png").string(), d, 0.0002);
  expectOneLineError(runUpd(cmd), "depth/2.png not found");

  // An 8-bit PNG where a depth image is listed (the RGB image by mistake).
  cv::imwrite((dir / "depth" / "2.png").string(), cv::Mat(3, 4, CV_8UC1, cv::Scalar(9)));
  expectOneLineError(runUpd(cmd), "2.png: 8-bit");

  std::ofstream(dir / "depth.txt") << "1.0 depth/1.png\n";
  K.fx = 0;
  writeCameraInfo(dir / "calib.yaml", K);
  expectOneLineError(runUpd(cmd), "calib.yaml: camera_matrix fx");
  EXPECT_FALSE(fs::exists(tmp.path() / "out" / "summary.json"));
}

TEST(DepthPng, AnalyzeBadInputNamesTheFile) {
  const test::TempDir tmp("png-bad");
  core::CameraIntrinsics K;
  writeCameraInfo(tmp.path() / "calib.yaml", K);
  const CmdResult missing = runUpd("analyze " + (tmp.path() / "none.png").string() +
                                   " --intrinsics " + (tmp.path() / "calib.yaml").string());
  expectOneLineError(missing, "none.png: not found");
  const CmdResult no_calib = runUpd("analyze " + (tmp.path() / "none.png").string());
  EXPECT_EQ(no_calib.exit_code, 2) << no_calib.output;
  EXPECT_NE(no_calib.output.find("--intrinsics"), std::string::npos) << no_calib.output;
}

}  // namespace
}  // namespace upd
