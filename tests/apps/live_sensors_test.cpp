// `upd live --sensors` end to end with the real binary: a stereo camera replayed by MRPT's
// image_dir grabber over real pairs, recorded with --record, and played back by `upd playback`
// into the same map; bad sensor files and option mixes fail with one line.
#include "apps/run_upd.h"
#include "mrpt_bridge/sensor_stereo_dir.h"
#include "temp_dir.h"
#include "test_data.h"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

namespace fs = std::filesystem;
using upd::test::runCommand;
using upd::test::runUpd;

namespace {

nlohmann::json readJson(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

// The shipped navigation config without what the live loop adds to the map and `upd playback`
// does not (docs/SENSORS.md): the missing-ground evidence, the step edges and the navigator's own
// d_m. With them off, both build the same map.
std::string navConfigAsPlayback(const upd::test::TempDir& dir) {
  const fs::path config = fs::path(UPD_SOURCE_DIR) / "config";
  std::string text = upd::test::readFileBytes(config / "dune-nav.ini");
  text = std::regex_replace(text, std::regex("\\[NegativeObstacleParams\\]\\nenabled = true"),
                            "[NegativeObstacleParams]\nenabled = false");
  text = std::regex_replace(text, std::regex("\\[StepEdgeParams\\]\\nenabled = true"),
                            "[StepEdgeParams]\nenabled = false");
  text = std::regex_replace(text, std::regex("\\nupd_radius_m = [0-9.]+"), "\nupd_radius_m = 0");
  text = std::regex_replace(text, std::regex("ptg_ini = ptg-dune.ini"),
                            "ptg_ini = " + (config / "ptg-dune.ini").string());
  const std::string path = dir.file("nav.ini");
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST(LiveSensors, AnUnknownDriverClassIsOneLineAndStatus1) {
  const upd::test::TempDir dir;
  std::ofstream(dir.file("s.ini")) << "[CAM]\ndriver = CNoSuchSensor\n";
  const auto r = runUpd("live --sensors " + dir.file("s.ini"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(r.output, "upd live: error: sensor file " + dir.file("s.ini") +
                          " [CAM]: unknown driver class 'CNoSuchSensor' (not a sensor of MRPT's "
                          "hwdrivers)\n");
}

TEST(LiveSensors, OneSourceAtATime) {
  const auto r = runUpd("live --sensors a.ini --oni b.oni");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("choose one source"), std::string::npos) << r.output;
}

TEST(LiveSensors, ARecordedStereoRunPlaysBackIntoTheSameMap) {
  UPD_REQUIRE_SHARED_FILE(yaml, "rtabmap/stereo_rect/stereo_left.yaml");
  const upd::test::TempDir dir;
  const std::string ini = upd::test::writeStereoImageDir(fs::path(yaml).parent_path(), dir.path());
  const std::string config = (fs::path(UPD_SOURCE_DIR) / "config" / "dune-kinect.ini").string();
  const std::string rawlog = dir.file("run.rawlog");
  const auto live = runUpd("live --sensors " + ini + " --config " + config + " --nav-config " +
                           navConfigAsPlayback(dir) + " --output " + dir.file("live") +
                           " --record " + rawlog);
  ASSERT_EQ(live.exit_code, 0) << live.output;
  const auto summary = readJson(dir.path() / "live" / "summary.json");
  EXPECT_EQ(summary["end"], "end of the recording");
  EXPECT_EQ(summary["frames"], 2);
  EXPECT_EQ(summary["recording"]["observations"], 4);  // 2 pairs, each after its odometry
  EXPECT_GT(summary["map_known_cells"].get<int>(), 500);
  EXPECT_TRUE(fs::exists(rawlog));
  EXPECT_FALSE(fs::exists(rawlog + ".part"));

  const auto play = runUpd("playback " + rawlog + " --config " + config + " --output " +
                           dir.file("play") + " --quiet");
  ASSERT_EQ(play.exit_code, 0) << play.output;
  EXPECT_EQ(readJson(dir.path() / "play" / "summary.json")["pose_source"], "odometry observations");
  const std::string live_map = upd::test::readFileBytes(dir.path() / "live" / "map.pgm");
  ASSERT_FALSE(live_map.empty());
  EXPECT_TRUE(live_map == upd::test::readFileBytes(dir.path() / "play" / "map.pgm"));

  if (!fs::exists("/usr/bin/rawlog-edit")) GTEST_SKIP() << "rawlog-edit not installed";
  const auto info = runCommand("/usr/bin/rawlog-edit --info -i " + rawlog);
  EXPECT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("Observations format               : Yes"), std::string::npos)
      << info.output;
  EXPECT_NE(info.output.find("ODOMETRY, STEREO"), std::string::npos) << info.output;
}
