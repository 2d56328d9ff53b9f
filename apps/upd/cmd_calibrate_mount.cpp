// `upd calibrate-mount`: the camera's height, pitch and roll on the robot measured from the
// floor in its first frames (a rawlog, a depth PNG, a PCD/PLY/XYZ frame in the camera-optical
// frame, an OpenNI2 .oni recording), printed and written as a [CameraMountParams] section.
#include "calibrate_mount.h"
#include "cli.h"
#include "commands.h"
#include "depth_input.h"

#include "upd/core/camera.h"
#include "upd/io/atomic_file.h"
#include "upd/io/cloud_io.h"
#include "upd/mrpt_bridge/depth_files.h"
#include "upd/mrpt_bridge/ini_params.h"
#include "upd/mrpt_bridge/observation_cloud.h"
#include "upd/mrpt_bridge/pose_source.h"
#include "upd/mrpt_bridge/rawlog_reader.h"
#include "upd/nav/nav_config.h"
#include "upd/sim/mount_calibration.h"

#ifdef UPD_HAVE_OPENNI2
#include "upd/openni2/depth_camera.h"
#endif

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationStereoImages.h>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <ostream>

namespace upd::app {

const char* const kCalibrateMountUsage =
    "usage: upd calibrate-mount INPUT [options]\n"
    "  Finds the floor in the first frames of a static camera (RANSAC on the points below the\n"
    "  camera, then a least-squares refit) and prints the camera mount it implies:\n"
    "  [CameraMountParams] height_m, pitch_deg and roll_deg, with the plane's RMS residual and\n"
    "  the share of the points on it. forward_m, left_m and image_downscale are kept from the\n"
    "  navigation config. Put the robot on a level floor with the floor in view. No floor:\n"
    "  one line saying why, exit status 1, nothing written.\n\n"
    "INPUT (every frame in the camera's optical frame: x right, y down, z forward):\n"
    "  RUN.rawlog      its 3D observations (range images, stereo pairs, point clouds)\n"
    "  DEPTH.png       a 16-bit depth image, with --intrinsics\n"
    "  FRAME.pcd|.ply|.xyz  an (organized) cloud in the camera-optical frame\n"
    "  REC.oni         an OpenNI2 recording (when upd was built with OpenNI2)\n\n"
    "options:\n"
    "  --frames N          frames to use (default 5; a rawlog's first N 3D observations)\n"
    "  --intrinsics F.yaml camera calibration of a depth PNG (OpenCV or ROS camera_info YAML)\n"
    "  --depth-scale S     metres per depth unit of a PNG (default 0.001: millimetres)\n"
    "  --nav-config FILE   the configured mount (default config/dune-nav.ini): the prior up\n"
    "                      direction and the fields the floor does not measure\n"
    "  --floor-config FILE [FloorPlaneParams] of the floor search (docs/PARAMETERS.md)\n"
    "  --output FILE.ini   write the [CameraMountParams] section (for --mount of upd live)\n";

namespace {

// The camera-optical axes in an MRPT sensor frame (x forward, y left, z up).
Eigen::Isometry3d opticalInSensor() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = sim::opticalInMount();
  return T;
}

struct Frames {
  std::vector<core::PointCloud> clouds;  ///< camera-optical frame
  /// The recorded camera-optical frame on the robot (a rawlog's sensor pose): the prior up.
  std::optional<Eigen::Isometry3d> recorded_optical_on_robot;
};

// Up to n 3D observations of a rawlog, each moved back from the robot frame to its camera's
// optical frame (the rawlog's sensor pose is the one being calibrated).
void rawlogFrames(const std::string& path, int n, Frames& out) {
  mrpt_bridge::RawlogReader reader(path);
  mrpt_bridge::RawlogEntry entry;
  core::PointCloud cloud;
  Eigen::Isometry3d optical_on_robot;
  while (static_cast<int>(out.clouds.size()) < n && reader.next(entry)) {
    if (!entry.observation || !opticalFrameCloud(*entry.observation, cloud, &optical_on_robot)) {
      continue;
    }
    out.clouds.push_back(cloud);
    if (!out.recorded_optical_on_robot) out.recorded_optical_on_robot = optical_on_robot;
  }
}

// The configured mount, with the pitch and roll of the recorded sensor pose when there is one.
sim::CameraMountParams priorMount(const Frames& f, sim::CameraMountParams configured) {
  if (!f.recorded_optical_on_robot) return configured;
  core::FloorPlane up;  // the robot's z in the camera frame, as a floor normal
  up.normal = f.recorded_optical_on_robot->linear().transpose() * Eigen::Vector3d::UnitZ();
  const core::MountPose m = core::mountFromFloor(up);
  configured.pitch_rad = m.pitch_rad;
  configured.roll_rad = m.roll_rad;
  return configured;
}

#ifdef UPD_HAVE_OPENNI2
void oniFrames(const std::string& path, int n, Frames& out) {
  openni2::OpenNI2Camera camera(path);
  openni2::DepthFrame frame;
  while (static_cast<int>(out.clouds.size()) < n && camera.read(frame)) {
    out.clouds.push_back(core::depthToCloud(frame.depth, frame.K));
  }
}
#endif

struct CalibrateOptions {
  std::string input;
  int frames = 5;
  std::optional<std::string> intrinsics, output, floor_config;
  double depth_scale = 0.001;
  std::string nav_path;
};

Frames readFrames(const CalibrateOptions& o) {
  const std::string ext = std::filesystem::path(o.input).extension().string();
  Frames frames;
  if (ext == ".rawlog") {
    rawlogFrames(o.input, o.frames, frames);
  } else if (ext == ".png") {
    if (!o.intrinsics) throw UsageError("a depth PNG needs --intrinsics CALIB.yaml");
    const auto calib = mrpt_bridge::loadDepthCalibration(*o.intrinsics);
    frames.clouds.push_back(
        core::depthToCloud(depthImageOf(o.input, calib, o.depth_scale), calib.K));
  } else if (ext == ".oni") {
#ifdef UPD_HAVE_OPENNI2
    oniFrames(o.input, o.frames, frames);
#else
    throw std::runtime_error("cannot play " + o.input + ": upd was built without OpenNI2");
#endif
  } else {
    frames.clouds.push_back(io::readCloud(o.input));  // names the formats it knows
  }
  if (frames.clouds.empty()) throw std::runtime_error(o.input + ": no 3D frame to calibrate on");
  return frames;
}

CalibrateOptions parseCalibrateOptions(const std::vector<std::string>& argv) {
  const Args args(argv, {"--frames", "--intrinsics", "--depth-scale", "--nav-config",
                         "--floor-config", "--output"},
                  {});
  if (args.positionals().size() != 1) throw UsageError("expected exactly one INPUT");
  CalibrateOptions o;
  o.input = args.positionals()[0];
  o.frames = args.integer("--frames").value_or(5);
  if (o.frames < 1) throw UsageError("option --frames = " + std::to_string(o.frames) + ": must be >= 1");
  o.intrinsics = args.str("--intrinsics");
  o.depth_scale = args.number("--depth-scale").value_or(0.001);
  if (!(o.depth_scale > 0)) {
    throw UsageError("option --depth-scale = " + std::to_string(o.depth_scale) + ": must be > 0");
  }
  o.nav_path = args.str("--nav-config").value_or(nav::defaultConfigDir() + "/dune-nav.ini");
  o.floor_config = args.str("--floor-config");
  o.output = args.str("--output");
  return o;
}

}  // namespace

void loadMountFile(const std::string& mount_ini, sim::CameraMountParams& mount) {
  mrpt_bridge::IniReader ini(mount_ini);
  ini.read("CameraMountParams", mount);
  ini.checkAllKeysKnown();
}

void remount(mrpt::obs::CObservation& obs, const sim::CameraMountParams& mount) {
  if (dynamic_cast<mrpt::obs::CObservation3DRangeScan*>(&obs)) {
    obs.setSensorPose(mrpt_bridge::toCPose3D(sim::mountOnRobot(mount)));
  } else if (dynamic_cast<mrpt::obs::CObservationStereoImages*>(&obs)) {
    obs.setSensorPose(mrpt_bridge::toCPose3D(sim::cameraOnRobot(mount)));
  }
}

sim::CameraMountParams autoMount(const std::function<bool(core::PointCloud&)>& next_cloud,
                                 const sim::CameraMountParams& configured, int frames) {
  std::vector<core::PointCloud> clouds(static_cast<std::size_t>(frames));
  std::vector<const core::PointCloud*> views;
  for (auto& c : clouds) {
    if (!next_cloud(c)) break;
    views.push_back(&c);
  }
  const sim::MountCalibration cal = sim::requireCalibratedMount(views, configured);
  std::printf("auto mount: %s\n", cal.summary().c_str());
  return cal.mount;
}

bool opticalFrameCloud(const mrpt::obs::CObservation& obs, core::PointCloud& cloud,
                       Eigen::Isometry3d* optical_on_robot) {
  const mrpt_bridge::ObservationCloud c = mrpt_bridge::toCloud(obs);
  if (!c.ok() || c.cloud_in_robot.countFinite() == 0) return false;
  // A stereo pair's sensor pose is its left optical frame already.
  const Eigen::Isometry3d optical = c.source_class == "CObservationStereoImages"
                                        ? c.sensor_pose_on_robot
                                        : c.sensor_pose_on_robot * opticalInSensor();
  cloud = core::transformCloud(c.cloud_in_robot, optical.inverse());
  if (optical_on_robot) *optical_on_robot = optical;
  return true;
}

int runCalibrateMount(const std::vector<std::string>& argv) {
  const CalibrateOptions o = parseCalibrateOptions(argv);
  const nav::NavConfig config =
      nav::loadNavConfig(nav::defaultConfigDir() + "/dune-kinect.ini", o.nav_path);
  core::FloorPlaneParams floor_params;
  if (o.floor_config) {
    mrpt_bridge::IniReader ini(*o.floor_config);
    ini.read("FloorPlaneParams", floor_params);
    ini.checkAllKeysKnown();
  }
  const Frames frames = readFrames(o);
  std::vector<const core::PointCloud*> views;
  for (const auto& f : frames.clouds) views.push_back(&f);
  const sim::MountCalibration cal =
      sim::calibrateMount(views, priorMount(frames, config.camera), floor_params);
  sim::CameraMountParams mount = config.camera;  // forward, left and downscale as configured
  if (!cal.ok()) throw std::runtime_error(o.input + ": " + cal.summary());
  mount.height_m = cal.mount.height_m;
  mount.pitch_rad = cal.mount.pitch_rad;
  mount.roll_rad = cal.mount.roll_rad;
  const std::string section =
      sim::mountIniSection(mount, "upd calibrate-mount " + o.input + ": " + cal.summary());
  std::printf("%s: %s\n\n%s", o.input.c_str(), cal.summary().c_str(), section.c_str());
  if (o.output) {
    io::writeFileAtomically(*o.output, [&](std::ostream& os) { os << section; });
    std::printf("\nwrote %s (use it with: upd live --mount %s)\n", o.output->c_str(),
                o.output->c_str());
  }
  return 0;
}

}  // namespace upd::app
