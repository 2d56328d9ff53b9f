#include "playback_tum.h"

#include "cli.h"
#include "commands.h"
#include "depth_input.h"

#include "upd/mrpt_bridge/gz_output_stream.h"
#include "upd/io/atomic_file.h"
#include "upd/mrpt_bridge/depth_files.h"
#include "upd/mrpt_bridge/pose_source.h"
#include "upd/sim/robot.h"

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>

namespace upd::app {

namespace {

namespace fs = std::filesystem;

struct TumFrame {
  double t_s;
  std::string png;  ///< absolute
};

// depth.txt: `timestamp file` per line; # comments and blank lines skipped.
std::vector<TumFrame> readDepthList(const fs::path& dir) {
  const fs::path list = dir / "depth.txt";
  std::ifstream in(list);
  if (!in) throw std::runtime_error(list.string() + ": not found (a TUM folder lists its depth images there)");
  std::vector<TumFrame> frames;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream is(line);
    TumFrame f{};
    std::string name;
    if (!(is >> f.t_s >> name) || !std::isfinite(f.t_s)) {
      throw std::runtime_error(list.string() + " line " + std::to_string(n) +
                               ": expected 'timestamp depth/NAME.png', got '" + line + "'");
    }
    f.png = (dir / name).string();
    if (!fs::is_regular_file(f.png)) {
      throw std::runtime_error(list.string() + " line " + std::to_string(n) + ": " + f.png +
                               " not found");
    }
    frames.push_back(f);
  }
  if (frames.empty()) throw std::runtime_error(list.string() + ": lists no depth image");
  return frames;
}

struct TumOptions {
  fs::path dir, out_dir;
  mrpt_bridge::DepthCalibration calib;
  double metres_per_unit = 0.0002;
  std::string poses;
  std::vector<std::string> playback_argv;  ///< the rest, for runPlayback
};

core::CameraIntrinsics cameraByName(const std::optional<std::string>& name, const fs::path& dir) {
  if (name) return mrpt_bridge::tumIntrinsics(*name);
  const std::string folder = fs::absolute(dir).lexically_normal().filename().string();
  for (const char* fr : {"freiburg1", "freiburg2", "freiburg3"}) {
    if (folder.find(fr) != std::string::npos) return mrpt_bridge::tumIntrinsics(fr);
  }
  throw UsageError("TUM folder " + dir.string() +
                   ": give --intrinsics CALIB.yaml or --tum-camera freiburg1|freiburg2|"
                   "freiburg3|ros (its name names no freiburg camera)");
}

// Splits off the TUM options; the others go to runPlayback.
TumOptions parseTumOptions(const std::vector<std::string>& argv) {
  TumOptions o;
  std::optional<std::string> intrinsics, camera, scale, poses, out;
  o.dir = argv.at(0);
  for (std::size_t i = 1; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    const auto take = [&](std::optional<std::string>& v) {
      if (i + 1 >= argv.size()) throw UsageError("option " + a + " needs a value");
      v = argv[++i];
    };
    if (a == "--intrinsics") take(intrinsics);
    else if (a == "--tum-camera") take(camera);
    else if (a == "--depth-scale") take(scale);
    else if (a == "--poses") take(poses);
    else o.playback_argv.push_back(a);
    if (a == "--output" && i + 1 < argv.size()) out = argv[i + 1];
  }
  if (!out) throw UsageError("--output DIR is required");
  o.out_dir = *out;
  if (scale) {
    try {
      o.metres_per_unit = std::stod(*scale);
    } catch (const std::exception&) {
      throw UsageError("option --depth-scale = '" + *scale + "': not a number");
    }
    if (!(o.metres_per_unit > 0)) throw UsageError("option --depth-scale = " + *scale + ": must be > 0");
  }
  if (intrinsics) {
    o.calib = mrpt_bridge::loadDepthCalibration(*intrinsics);
  } else {
    o.calib.K = cameraByName(camera, o.dir);
  }
  o.poses = poses ? *poses : (o.dir / "groundtruth.txt").string();
  if (!fs::is_regular_file(o.poses)) {
    throw std::runtime_error(o.poses + ": not found (a TUM folder's camera poses; or give --poses)");
  }
  return o;
}

// One depth image as a range scan in TUM's units; the optical frame is the robot frame.
mrpt::obs::CObservation3DRangeScan::Ptr tumScan(const core::DepthImage& depth, const TumOptions& o,
                                                double t_s) {
  auto obs = mrpt::obs::CObservation3DRangeScan::Create();
  obs->sensorLabel = "TUM_DEPTH";
  obs->timestamp = mrpt::Clock::fromDouble(t_s);
  obs->hasRangeImage = true;
  obs->range_is_depth = true;
  obs->rangeUnits = static_cast<float>(o.metres_per_unit);
  obs->maxRange = static_cast<float>(65535 * o.metres_per_unit);
  obs->rangeImage_setSize(depth.height, depth.width);
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      obs->rangeImage(v, u) = static_cast<std::uint16_t>(std::lround(depth.at(u, v) / o.metres_per_unit));
    }
  }
  const core::CameraIntrinsics& K = o.calib.K;
  obs->cameraParams.ncols = K.width;
  obs->cameraParams.nrows = K.height;
  obs->cameraParams.setIntrinsicParamsFromValues(K.fx, K.fy, K.cx, K.cy);
  obs->cameraParamsIntensity = obs->cameraParams;
  // The MRPT sensor frame (x forward, y left, z up) in the optical frame.
  Eigen::Isometry3d sensor_in_optical = Eigen::Isometry3d::Identity();
  sensor_in_optical.linear() = sim::opticalInMount().transpose();
  obs->sensorPose = mrpt_bridge::toCPose3D(sensor_in_optical);
  return obs;
}

// The folder as a rawlog (observations only), written atomically.
void writeSequence(const std::vector<TumFrame>& frames, const TumOptions& o, const fs::path& rawlog) {
  io::writeFileAtomicallyVia(rawlog.string(), [&](const std::string& tmp) {
    mrpt_bridge::GzOutputStream out(tmp);
    auto arch = mrpt::serialization::archiveFrom(out);
    for (const TumFrame& f : frames) {
      arch << *tumScan(depthImageOf(f.png, o.calib, o.metres_per_unit), o, f.t_s);
    }
    out.close();
  });
}

}  // namespace

bool isTumPlayback(const std::vector<std::string>& argv) {
  return !argv.empty() && argv[0][0] != '-' && fs::is_directory(argv[0]);
}

int runTumPlayback(const std::vector<std::string>& argv) {
  const TumOptions o = parseTumOptions(argv);
  const std::vector<TumFrame> frames = readDepthList(o.dir);
  fs::create_directories(o.out_dir);
  const fs::path rawlog = o.out_dir / "sequence.rawlog";
  writeSequence(frames, o, rawlog);
  std::printf("%s: %zu depth images (fx %.1f, %g m per unit) -> %s\n", o.dir.c_str(),
              frames.size(), o.calib.K.fx, o.metres_per_unit, rawlog.c_str());
  std::vector<std::string> args{rawlog.string(), "--poses", o.poses};
  args.insert(args.end(), o.playback_argv.begin(), o.playback_argv.end());
  return runPlayback(args);
}

}  // namespace upd::app
