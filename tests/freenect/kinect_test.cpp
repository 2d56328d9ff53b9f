// The Kinect v1 route without hardware: libfreenect's disparity-to-millimetre conversion, and
// `upd live --kinect` under fakenect (libfreenect's replay library) on recordings written from
// simulated frames: the frames arrive with their depth, and a device that repeats its last
// frame is detected and the robot stopped.
#include "upd/freenect/kinect.h"
#include "upd/mrpt_bridge/rawlog_reader.h"
#include "upd/sim/render.h"

#include "apps/image_colours.h"
#include "apps/run_upd.h"
#include "apps/xvfb_server.h"
#include "temp_dir.h"

#include <mrpt/obs/CObservation3DRangeScan.h>
#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>

namespace fs = std::filesystem;
namespace fn = upd::freenect;

namespace {

const char* const kFakenect = "/usr/lib/x86_64-linux-gnu/fakenect/libfreenect.so";

// The depth step of one raw disparity unit at raw.
double stepMm(std::uint16_t raw) { return fn::rawToMm(raw + 1) - fn::rawToMm(raw); }

// A flat floor seen by a Kinect 0.6 m up, looking 30 deg down; the i-th frame from 0.2 m
// further back each time (so frames differ).
upd::core::DepthImage floorFrame(int i) {
  const upd::sim::Terrain floor(Eigen::Vector2d(-10, -10), Eigen::Vector2d(10, 10));
  const Eigen::Vector3d eye(-0.2 * i, 0, 0.6);
  const auto pose = upd::sim::cameraPoseLookingAt(eye, eye + Eigen::Vector3d(1, 0, -std::tan(0.52)));
  upd::sim::DepthNoise noise;
  noise.sigma_coeff_per_m = 0;
  noise.max_range_m = 6.0;
  return upd::sim::renderDepth(floor, pose, fn::intrinsicsOf(), noise, 1);
}

std::string navConfig(const upd::test::TempDir& dir) {
  const fs::path config = fs::path(UPD_SOURCE_DIR) / "config";
  std::string text = upd::test::readFileBytes(config / "dune-nav.ini");
  text = std::regex_replace(text, std::regex("ptg_ini = ptg-dune.ini"),
                            "ptg_ini = " + (config / "ptg-dune.ini").string());
  const std::string path = dir.file("nav.ini");
  std::ofstream(path) << text;
  return path;
}

upd::test::CmdResult liveUnderFakenect(const upd::test::TempDir& dir, const std::string& rec,
                                       const std::string& args) {
  return upd::test::runCommand("FAKENECT_PATH=" + rec + " LD_PRELOAD=" + kFakenect + " " +
                               UPD_BINARY + " live --kinect --nav-config " + navConfig(dir) +
                               " " + args);
}

std::vector<std::shared_ptr<mrpt::obs::CObservation3DRangeScan>> scansOf(const std::string& f) {
  std::vector<std::shared_ptr<mrpt::obs::CObservation3DRangeScan>> out;
  upd::mrpt_bridge::RawlogReader reader(f);
  upd::mrpt_bridge::RawlogEntry e;
  while (reader.next(e)) {
    if (auto s = std::dynamic_pointer_cast<mrpt::obs::CObservation3DRangeScan>(e.observation)) {
      out.push_back(s);
    }
  }
  return out;
}

}  // namespace

TEST(Kinect, RawDisparityAndMillimetresRoundTrip) {
  EXPECT_EQ(fn::rawToMm(2047), 0.0);
  EXPECT_EQ(fn::mmToRaw(0), 2047);
  EXPECT_EQ(fn::mmToRaw(20000), 2047);  // beyond the 10 m libfreenect reports
  for (double mm = 500; mm <= 8000; mm += 37.5) {
    const std::uint16_t raw = fn::mmToRaw(mm);
    ASSERT_LT(raw, 2047) << mm;
    EXPECT_LE(std::abs(fn::rawToMm(raw) - mm), 0.5 * stepMm(raw) + 1e-9) << mm;
  }
  // The Kinect's raw 11-bit value (libfreenect's "shift") grows with depth.
  EXPECT_LT(fn::mmToRaw(1000), fn::mmToRaw(2000));
  const auto K = fn::intrinsicsOf();
  EXPECT_NEAR(K.fx, 575.8, 0.1);  // 120 mm / (2 * 0.1042 mm)
  EXPECT_EQ(K.cx, 320.0);
}

TEST(Kinect, FakenectFramesArriveWithTheirDepth) {
  if (!fs::exists(kFakenect)) GTEST_SKIP() << kFakenect << " not installed (libfreenect-bin)";
  const upd::test::TempDir dir;
  const fs::path rec = dir.path() / "rec";
  fs::create_directories(rec);
  std::vector<upd::core::DepthImage> frames;
  for (int i = 0; i < 3; ++i) {
    frames.push_back(floorFrame(i));
    fn::writeFakenectDepth(rec.string(), frames.back(), 0.01 * i, 1000 + 33 * i);
  }
  const auto r = liveUnderFakenect(dir, rec.string(),
                                   "--record " + dir.file("run.rawlog") + " --output " +
                                       dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("source: fakenect recording " + rec.string()), std::string::npos);
  const auto scans = scansOf(dir.file("run.rawlog"));
  ASSERT_EQ(scans.size(), 3u) << r.output;
  const int ds = 4;  // [CameraMountParams] image_downscale of config/dune-nav.ini
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const auto& s = *scans[i];
    ASSERT_EQ(s.rangeImage.cols(), 640 / ds);
    EXPECT_NEAR(s.cameraParams.fx(), fn::intrinsicsOf().fx / ds, 1e-6);
    std::size_t valid = 0;
    for (int v = 0; v < s.rangeImage.rows(); ++v) {
      for (int u = 0; u < s.rangeImage.cols(); ++u) {
        const double want_mm = 1000.0 * frames[i].at(u * ds, v * ds);
        const double got_mm = s.rangeImage(v, u);
        if (want_mm <= 0) continue;
        ++valid;
        ASSERT_LE(std::abs(got_mm - want_mm), 0.5 * stepMm(fn::mmToRaw(want_mm)) + 1.0)
            << "frame " << i << " pixel " << u << "," << v;
      }
    }
    EXPECT_GT(valid, 10000u);
  }
  std::ifstream in(dir.path() / "out" / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["frames"], 3);
  EXPECT_GT(summary["map_known_cells"].get<int>(), 100);
}

// A recording the disk refuses (/dev/full) stops with one line, as rosbag's does; the run
// goes on to the end of the source, its outputs are written, and the exit status is 1.
TEST(Kinect, ARecordingTheDiskRefusesStopsAndTheRunGoesOn) {
  if (!fs::exists(kFakenect)) GTEST_SKIP() << kFakenect << " not installed (libfreenect-bin)";
  if (!fs::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this system";
  const upd::test::TempDir dir;
  const fs::path rec = dir.path() / "rec";
  fs::create_directories(rec);
  for (int i = 0; i < 4; ++i) {
    fn::writeFakenectDepth(rec.string(), floorFrame(i), 0.01 * i, 1000 + 33 * i);
  }
  const std::string run = dir.file("run.rawlog");
  fs::create_symlink("/dev/full", run + ".part");
  const auto r =
      liveUnderFakenect(dir, rec.string(), "--record " + run + " --output " + dir.file("out"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("upd live: recording stopped: cannot write " + run +
                          ".part: No space left on device; the run goes on"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("end of the recording: 4 frames"), std::string::npos) << r.output;
  // (/dev/full takes nothing: no member of the recording is complete)
  EXPECT_NE(r.output.find("upd live: error: the recording stopped: cannot write " + run +
                          ".part: No space left on device; " + run +
                          ".part holds the first 0 of the "),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(run));
  std::ifstream in(dir.path() / "out" / "summary.json");
  ASSERT_TRUE(in) << r.output;
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["frames"], 4);
  EXPECT_EQ(summary["recording"]["path"], run + ".part");
  EXPECT_EQ(summary["recording"]["observations"], 0);
  EXPECT_GT(summary["recording"]["observations_handed"].get<int>(), 0);
  EXPECT_EQ(summary["recording"]["error"],
            "cannot write " + run + ".part: No space left on device");
}

TEST(Kinect, ADeviceRepeatingItsFrameStopsTheRobot) {
  if (!fs::exists(kFakenect)) GTEST_SKIP() << kFakenect << " not installed (libfreenect-bin)";
  const upd::test::TempDir dir;
  const fs::path rec = dir.path() / "rec";
  fs::create_directories(rec);
  fn::writeFakenectDepth(rec.string(), floorFrame(0), 0.0, 7);
  // The same frame (device stamp 7) 30 times, 20 ms apart: a device stuck on its last frame.
  std::ofstream index(rec / "INDEX.txt", std::ios::app);
  for (int k = 1; k <= 30; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "d-%.6f-7.pgm", 0.02 * k);
    fs::create_symlink(rec / "d-0.000000-7.pgm", rec / name);
    index << name << "\n";
  }
  index.close();
  const auto r =
      liveUnderFakenect(dir, rec.string(), "--stale-timeout 0.2 --output " + dir.file("out"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("the source stopped: no new frame for"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("robot stopped"), std::string::npos) << r.output;
  std::ifstream in(dir.path() / "out" / "summary.json");
  const auto summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["end"], "source stopped");
  EXPECT_EQ(summary["frames"], 1);
  EXPECT_EQ(summary["source_stopped"]["robot_stopped"], true);
  EXPECT_GE(summary["source_stopped"]["stale_frames"].get<int>(), 1);
  EXPECT_GT(summary["source_stopped"]["silent_s"].get<double>(), 0.2);
}

// `upd live --auto-mount` on the Kinect route: the mount measured from the first frames is the
// camera's (0.6 m up, 30 deg down), and the floor it then maps is traversable.
TEST(Kinect, AutoMountMeasuresTheFloorAndMapsItTraversable) {
  if (!fs::exists(kFakenect)) GTEST_SKIP() << kFakenect << " not installed (libfreenect-bin)";
  const upd::test::TempDir dir;
  const fs::path rec = dir.path() / "rec";
  fs::create_directories(rec);
  for (int i = 0; i < 8; ++i) fn::writeFakenectDepth(rec.string(), floorFrame(i), 0.01 * i, 1000 + 33 * i);
  const auto r = liveUnderFakenect(dir, rec.string(), "--auto-mount --output " + dir.file("out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m,
                                std::regex("auto mount: floor found in 5 frames: height ([-0-9.]+) m, "
                                           "pitch ([-0-9.]+) deg")))
      << r.output;
  EXPECT_NEAR(std::stod(m[1]), 0.6, 0.03) << r.output;
  EXPECT_NEAR(std::abs(std::stod(m[2])), 0.52 * 180 / M_PI, 1.5) << r.output;
  std::ifstream in(dir.file("out") + "/summary.json");
  const auto j = nlohmann::json::parse(in);
  const double known = j.at("map_known_cells").get<double>();
  EXPECT_GT(known, 100) << j.dump();
  EXPECT_LE(j.at("map_non_traversable_cells").get<double>(), 0.02 * known) << j.dump();
}

// `upd live --view` on the Kinect route in a virtual X server: the window of `upd view` follows
// the robot over the floor it maps (green: planes), the robot's box is drawn (orange), the
// screenshot of the last view is written, and the run ends with status 0 (no crash when the
// window's thread meets the process's exit).
TEST(Kinect, LiveViewShowsTheMappedFloorAndTheRobot) {
  if (!fs::exists(kFakenect)) GTEST_SKIP() << kFakenect << " not installed (libfreenect-bin)";
  const upd::test::XvfbServer x;
  if (!x.available()) GTEST_SKIP() << "Xvfb is not installed: the live view is not tested";
  const upd::test::TempDir dir;
  const fs::path rec = dir.path() / "rec";
  fs::create_directories(rec);
  for (int i = 0; i < 6; ++i) fn::writeFakenectDepth(rec.string(), floorFrame(i), 0.01 * i, 1000 + 33 * i);
  const std::string png = dir.file("live.png");
  const auto r = upd::test::runCommand("DISPLAY=" + x.display() + " FAKENECT_PATH=" + rec.string() +
                                       " LD_PRELOAD=" + kFakenect + " " + UPD_BINARY +
                                       " live --kinect --nav-config " + navConfig(dir) +
                                       " --view --screenshot " + png);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const mrpt::img::CImage img = upd::test::loadPng(png);
  ASSERT_EQ(img.getWidth(), 1280u);
  const upd::test::Counts c = upd::test::countColours(img, 1280 - 170, 40);
  EXPECT_GT(c.green, 20000u) << "the floor: planes (zeta 1) and traversable cells";
  EXPECT_GT(c.orange, 100u) << "the robot";
  EXPECT_LT(c.red, c.green / 20) << "a flat floor holds no obstacle";
}

TEST(Kinect, LiveScreenshotNeedsTheView) {
  const auto r = upd::test::runUpd("live --kinect --screenshot x.png");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--screenshot needs --view"), std::string::npos) << r.output;
}
