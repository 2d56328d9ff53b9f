// `upd bench-nav` as a user runs it: one short world with the oracle writes worlds.csv and
// summary.json with the documented fields, a second run agrees with its rows through --expect
// (the loop is deterministic), and bad options fail in one line.
#include "apps/run_upd.h"

#include "upd/nav/bench.h"

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

class BenchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("upd_bench_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    ::setenv("XDG_CACHE_HOME", (dir_ / "cache").c_str(), 1);  // a private PTG cache
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static std::size_t lines(const std::string& s) {
    return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
  }
  fs::path dir_;
};

TEST_F(BenchCli, OneOracleWorldWritesTheTableAndTheSummary) {
  const std::string out = path("bench");
  const CmdResult r = runUpd("bench-nav --worlds 1 --seed 4 --difficulty easy --obstacles truth "
                             "--goal-distance-m 4 --output " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("[  1/1] seed 4 (easy, truth)"), std::string::npos) << r.output;
  const auto rows = nav::readBenchCsv(out + "/worlds.csv");
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].seed, 4);
  EXPECT_EQ(rows[0].obstacles, "truth");
  EXPECT_GE(rows[0].optimal_path_m, 4.0);
  nlohmann::json s;
  std::ifstream(out + "/summary.json") >> s;
  for (const char* key : {"success_rate", "collisions", "timeouts", "time_ratio", "path_ratio",
                          "min_clearance_m", "failures"}) {
    EXPECT_TRUE(s.contains(key)) << key;
  }
  EXPECT_EQ(s["worlds"], 1);

  // The same run agrees with its own rows (the comparison itself: bench_test.cpp).
  EXPECT_EQ(runUpd("bench-nav --worlds 1 --seed 4 --difficulty easy --obstacles truth "
                   "--goal-distance-m 4 --quiet --output " + path("again") + " --expect " + out +
                   "/worlds.csv").exit_code,
            0);
}

TEST_F(BenchCli, BadOptionsFailInOneLine) {
  const std::string out = " --output " + path("x");
  const std::vector<std::string> bad = {
      "--worlds 0" + out, "--worlds 2" + out + " --obstacles lidar",
      "--worlds 2" + out + " --difficulty medium", "--worlds 2", "--output " + path("x"),
      "--worlds 2" + out + " --goal-distance-m 1"};
  for (const std::string& args : bad) {
    const CmdResult r = runUpd("bench-nav " + args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_EQ(lines(r.output), 1u) << args << ": " << r.output;
  }
  const CmdResult m = runUpd("bench-nav --worlds 1" + out + " --expect " + path("missing.csv"));
  EXPECT_EQ(m.exit_code, 1) << m.output;
  EXPECT_EQ(lines(m.output), 1u) << m.output;
  EXPECT_NE(m.output.find("missing.csv"), std::string::npos) << m.output;
  EXPECT_EQ(runUpd("bench-nav --help").exit_code, 0);
}

}  // namespace
}  // namespace upd
