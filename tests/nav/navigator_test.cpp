// MRPT's reactive navigator behind Navigator: it drives the base to a goal, writes a navlog that
// MRPT (and so navlog-viewer) reads back, keeps its PTG cache out of the working directory and
// reports bad configs clearly.
#include "upd/nav/navigator.h"

#include <gtest/gtest.h>
#include <mrpt/core/Clock.h>
#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/nav/reactive/CLogFileRecord.h>
#include <mrpt/serialization/CArchive.h>
#include <mrpt/serialization/CSerializable.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

namespace upd::nav {
namespace {

namespace fs = std::filesystem;

const std::string kPtg = std::string(UPD_SOURCE_DIR) + "/config/ptg-dune.ini";

class NavNavigatorRun : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("upd_nav_nav_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
    mrpt::Clock::setActiveClock(mrpt::Clock::Simulated);
  }
  void TearDown() override {
    mrpt::Clock::setActiveClock(mrpt::Clock::Realtime);
    fs::remove_all(dir_);
  }
  NavigatorSetup setup(const std::string& navlog = "") const {
    NavigatorSetup s;
    s.ptg_ini_path = kPtg;
    s.ptg_cache_dir = (dir_ / "cache").string();
    s.navlog_path = navlog;
    return s;
  }
  // Steps until the navigator stops or limit_s of simulated time pass.
  static int drive(Navigator& nav, SimulatedDiffDrive& base, double limit_s) {
    int steps = 0;
    while (base.timeS() < limit_s) {
      mrpt::Clock::setSimulatedTime(mrpt::Clock::fromDouble(1e9 + base.timeS()));
      ++steps;
      if (nav.step() != NavState::Navigating) break;
      base.advance(0.2);
    }
    return steps;
  }
  fs::path dir_;
};

TEST_F(NavNavigatorRun, ReachesANearGoalAndLogsEveryStep) {
  const fs::path cwd = fs::current_path();
  const auto before = std::distance(fs::directory_iterator(cwd), {});
  SimulatedDiffDrive base({0.0, 0.0, 0.0});
  ObstacleSource obstacles;
  const std::string navlog = (dir_ / "run.reactivenavlog").string();
  int steps = 0;
  {
    Navigator nav(base, obstacles, setup(navlog));
    nav.navigateTo({3.0, 1.0});
    steps = drive(nav, base, 30.0);
    const NavOutcome o = nav.outcome();
    EXPECT_EQ(o.state, NavState::Idle);
    EXPECT_TRUE(o.target_reached);
    EXPECT_TRUE(o.error_code.empty());
    const auto shape = nav.robotShape();
    ASSERT_EQ(shape.size(), 4u);
    // The shipped polygon: the 0.7 x 0.45 m footprint grown by 5 cm on every side.
    EXPECT_NEAR(std::abs(shape[0].x()), 0.40, 1e-6);
    EXPECT_NEAR(std::abs(shape[0].y()), 0.275, 1e-6);
    nav.closeLog();
  }
  EXPECT_LT(std::hypot(base.pose().x_m - 3.0, base.pose().y_m - 1.0), 0.35);

  // The navlog: one CLogFileRecord per step, as navlog-viewer reads it.
  ASSERT_TRUE(fs::exists(navlog));
  mrpt::io::CFileGZInputStream in(navlog);
  auto arch = mrpt::serialization::archiveFrom(in);
  int records = 0;
  for (;;) {
    mrpt::serialization::CSerializable::Ptr obj;
    try {
      arch >> obj;
    } catch (const std::exception&) {
      break;  // end of file
    }
    ASSERT_TRUE(std::dynamic_pointer_cast<mrpt::nav::CLogFileRecord>(obj));
    ++records;
  }
  EXPECT_GE(records, steps - 1);
  EXPECT_GT(records, 10);
  // No temporary directory left beside it, no PTG cache in the working directory.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), {}), 2);  // the log and cache/
  EXPECT_EQ(std::distance(fs::directory_iterator(cwd), {}), before);
  bool cached = false;
  for (const auto& e : fs::directory_iterator(dir_ / "cache")) {
    cached |= e.path().filename().string().rfind("ReacNavGrid_", 0) == 0;
  }
  EXPECT_TRUE(cached);
}

TEST_F(NavNavigatorRun, ABlockedGoalEndsWithTheNavigatorsError) {
  // A wall of obstacle points across the way, closer than the goal: no progress, then
  // ERR_CANNOT_REACH_TARGET after the configured timeout.
  SimulatedDiffDrive base({0.0, 0.0, 0.0});
  ObstacleSource obstacles;
  std::vector<Eigen::Vector2d> box;
  for (double t = -1.0; t <= 1.0; t += 0.05) {
    box.emplace_back(2.0 + t, -1.0);
    box.emplace_back(2.0 + t, 1.0);
    box.emplace_back(1.0, t);
    box.emplace_back(3.0, t);
  }
  obstacles.setFixedObstacles(box);
  NavigatorSetup s = setup();
  s.params.no_progress_timeout_s = 5.0;
  Navigator nav(base, obstacles, s);
  nav.navigateTo({2.0, 0.0});
  drive(nav, base, 60.0);
  const NavOutcome o = nav.outcome();
  EXPECT_EQ(o.state, NavState::Error);
  EXPECT_FALSE(o.target_reached);
  EXPECT_EQ(o.error_code, "ERR_CANNOT_REACH_TARGET");
  EXPECT_LT(base.timeS(), 59.0);  // ended by the navigator, not by the test's limit
}

// The PTG cache is shared by every process: the first one builds it in a private directory and
// renames it into place, so the cache directory is either absent or whole, and nothing else
// is left beside it; the next navigator reuses it.
TEST_F(NavNavigatorRun, PtgCacheAppearsWholeAndIsReused) {
  SimulatedDiffDrive base({0.0, 0.0, 0.0});
  ObstacleSource obstacles;
  const fs::path cache = dir_ / "cache";
  // Another process's view while the grids are built: the fewest files the cache ever showed.
  std::atomic<bool> built{false};
  std::size_t fewest_seen = SIZE_MAX;
  std::thread watcher([&] {
    while (!built) {
      std::error_code ec;
      std::size_t n = 0;
      for (fs::directory_iterator it(cache, ec), end; !ec && it != end; it.increment(ec)) ++n;
      if (!ec) fewest_seen = std::min(fewest_seen, n);
    }
  });
  { Navigator nav(base, obstacles, setup()); }
  built = true;
  watcher.join();
  ASSERT_TRUE(fs::is_directory(cache));
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(cache)) files.push_back(e.path().filename());
  EXPECT_FALSE(files.empty());
  if (fewest_seen != SIZE_MAX) {
    EXPECT_EQ(fewest_seen, files.size());
  }
  for (const auto& e : fs::directory_iterator(dir_)) {
    EXPECT_EQ(e.path().filename().string().find(".tmp."), std::string::npos) << e.path();
  }
  const auto stamp = fs::last_write_time(cache / files.front());
  { Navigator nav(base, obstacles, setup()); }
  EXPECT_EQ(fs::last_write_time(cache / files.front()), stamp);
}

TEST_F(NavNavigatorRun, BadConfigsAreReportedWithTheFile) {
  SimulatedDiffDrive base({0.0, 0.0, 0.0});
  ObstacleSource obstacles;
  NavigatorSetup s = setup();
  s.ptg_ini_path = (dir_ / "nope.ini").string();
  try {
    Navigator nav(base, obstacles, s);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nope.ini"), std::string::npos) << e.what();
  }
  s = setup();
  s.ptg_cache_dir.clear();
  EXPECT_THROW(Navigator(base, obstacles, s), std::invalid_argument);
  s = setup();
  s.params.target_allowed_distance_m = 0.0;
  EXPECT_THROW(Navigator(base, obstacles, s), std::invalid_argument);
}

}  // namespace
}  // namespace upd::nav
