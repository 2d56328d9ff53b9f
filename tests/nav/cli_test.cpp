// `upd navigate` and `upd live` as a user runs them: the outputs of a (short) closed-loop run,
// and clean one-line failures (no camera, bad scenario, bad option).
#include "apps/run_upd.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace upd {
namespace {

namespace fs = std::filesystem;

using test::CmdResult;
using test::runUpd;

class NavCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("upd_nav_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    // The PTG cache goes to the user's cache directory: a private one for the test.
    ::setenv("XDG_CACHE_HOME", (dir_ / "cache").c_str(), 1);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static std::size_t lines(const std::string& s) {
    return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
  }
  fs::path dir_;
};

TEST_F(NavCli, HelpListsBothCommands) {
  const CmdResult r = runUpd("--help");
  EXPECT_NE(r.output.find("navigate"), std::string::npos);
  EXPECT_NE(r.output.find("live"), std::string::npos);
  EXPECT_EQ(runUpd("navigate --help").exit_code, 0);
  EXPECT_EQ(runUpd("live --help").exit_code, 0);
}

TEST_F(NavCli, LiveWithoutACameraSaysSoInOneLine) {
  const CmdResult r = runUpd("live");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(lines(r.output), 1u) << r.output;
  EXPECT_NE(r.output.find("no OpenNI2 depth camera"), std::string::npos) << r.output;

  const CmdResult f = runUpd("live --oni " + path("missing.oni"));
  EXPECT_EQ(f.exit_code, 1);
  EXPECT_EQ(lines(f.output), 1u) << f.output;
  EXPECT_NE(f.output.find("missing.oni"), std::string::npos) << f.output;

  EXPECT_EQ(runUpd("live --navigate 1:2").exit_code, 2);
}

TEST_F(NavCli, BadScenarioAndOptionsStopBeforeRunning) {
  const CmdResult s = runUpd("navigate --scenario moon --output " + path("o"));
  EXPECT_NE(s.exit_code, 0);
  EXPECT_NE(s.output.find("corridor"), std::string::npos) << s.output;  // lists valid names
  EXPECT_EQ(runUpd("navigate --scenario ramp --obstacles lidar --output " + path("o")).exit_code,
            2);
  EXPECT_EQ(runUpd("navigate --scenario ramp").exit_code, 2);  // no --output
  const CmdResult c = runUpd("navigate --scenario ramp --output " + path("o") + " --nav-config " +
                             path("none.ini"));
  EXPECT_EQ(c.exit_code, 1);
  EXPECT_NE(c.output.find("none.ini"), std::string::npos) << c.output;
  EXPECT_FALSE(fs::exists(path("o") + "/summary.json"));
}

TEST_F(NavCli, AShortRunWritesEveryOutput) {
  const std::string out = path("run");
  const auto cwd_before = std::distance(fs::directory_iterator(fs::current_path()), {});
  const CmdResult r =
      runUpd("navigate --scenario rocks --output " + out + " --max-time-s 4 --quiet");
  EXPECT_EQ(r.exit_code, 3) << r.output;  // the time limit: not reached
  EXPECT_NE(r.output.find("time limit"), std::string::npos) << r.output;
  for (const char* f : {"navigation.reactivenavlog", "trajectory.csv", "path_map.png",
                        "path_truth.png", "summary.json"}) {
    EXPECT_GT(fs::exists(fs::path(out) / f) ? fs::file_size(fs::path(out) / f) : 0u, 0u) << f;
  }
  const auto j = nlohmann::json::parse(std::ifstream(fs::path(out) / "summary.json"));
  EXPECT_EQ(j["scenario"], "rocks");
  EXPECT_EQ(j["obstacles"], "upd");
  EXPECT_EQ(j["reached"], false);
  EXPECT_EQ(j["end"], "time limit");
  EXPECT_EQ(j["collisions"], 0);
  EXPECT_GE(j["sim_time_s"].get<double>(), 4.0);
  EXPECT_GT(j["path_length_m"].get<double>(), 0.5);
  EXPECT_GT(j["min_clearance_m"].get<double>(), 0.0);
  EXPECT_TRUE(j["navigator"].contains("state"));
  EXPECT_TRUE(j["navigator"].contains("error_code"));
  std::ifstream csv(fs::path(out) / "trajectory.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("t_s,x_m,y_m,yaw_rad", 0), 0u) << header;
  std::size_t rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_EQ(rows, j["steps"].get<std::size_t>() + 1);  // the start, then one per step
  // Nothing left in the working directory (MRPT's PTG cache and log go elsewhere).
  EXPECT_EQ(std::distance(fs::directory_iterator(fs::current_path()), {}), cwd_before);
  EXPECT_FALSE(fs::exists(fs::path(out) / ".navigation.reactivenavlog.tmp.d"));
}

}  // namespace
}  // namespace upd
