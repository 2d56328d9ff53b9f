// The navigation config: the shipped files load, the nav file is strict, paths resolve.
#include "upd/nav/nav_config.h"
#include "upd/nav/navigation_loop.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace core = upd::core;

namespace upd::nav {
namespace {

namespace fs = std::filesystem;

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config";

class NavTempIni : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("upd_nav_cfg_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p) << text;
    return p;
  }
  fs::path dir_;
};

TEST(NavShippedConfig, LoadsWithTheDuneValues) {
  const NavConfig c = loadNavConfig(kConfig + "/dune-kinect.ini", kConfig + "/dune-nav.ini");
  EXPECT_DOUBLE_EQ(c.pipeline.upd.radius_m, 0.5);  // from the robot config
  EXPECT_DOUBLE_EQ(c.body.length_m, 0.7);
  EXPECT_DOUBLE_EQ(c.body.width_m, 0.45);
  EXPECT_EQ(c.camera.image_downscale, 4);
  EXPECT_NEAR(c.camera.pitch_rad, 22.0 * core::kDegToRad, 1e-12);
  EXPECT_EQ(fs::path(c.ptg_ini).filename(), "ptg-dune.ini");
  EXPECT_TRUE(fs::exists(c.ptg_ini));
  EXPECT_FALSE(c.ptg_cache_dir.empty());
  EXPECT_NE(fs::path(c.ptg_cache_dir), fs::current_path());
}

// The loop compares the detectors at one neighbourhood: the roughness baseline runs at the
// UPD's navigation d_m, not at the robot config's mapping radius (a wider band, and several
// times the cost per frame).
TEST(NavShippedConfig, BaselineRunsAtTheUpdsNavigationRadius) {
  const NavConfig c = loadNavConfig(kConfig + "/dune-kinect.ini", kConfig + "/dune-nav.ini");
  ASSERT_GT(c.perception.upd_radius_m, 0.0);
  ASSERT_NE(c.baseline.radius_m, c.perception.upd_radius_m);  // the robot config's differs
  for (const auto d : {core::ObstacleDetector::Upd, core::ObstacleDetector::Roughness}) {
    const core::FrameScorerParams p = loopScorerParams(c, d);
    EXPECT_DOUBLE_EQ(p.pipeline.upd.radius_m, c.perception.upd_radius_m);
    EXPECT_DOUBLE_EQ(p.baseline.radius_m, c.perception.upd_radius_m);
    EXPECT_EQ(p.detector, d);
  }
  NavConfig keep = c;
  keep.perception.upd_radius_m = 0.0;  // 0: the robot config's radii
  const core::FrameScorerParams p = loopScorerParams(keep, core::ObstacleDetector::Roughness);
  EXPECT_DOUBLE_EQ(p.baseline.radius_m, c.baseline.radius_m);
  EXPECT_DOUBLE_EQ(p.pipeline.upd.radius_m, c.pipeline.upd.radius_m);
}

TEST_F(NavTempIni, UnknownKeysAndSectionsOfTheNavFileAreErrors) {
  const std::string robot = kConfig + "/dune-kinect.ini";
  const std::string bad_key =
      write("a.ini", "[NavigatorParams]\nptg_ini = x.ini\ntarget_alowed = 1\n");
  try {
    loadNavConfig(robot, bad_key);
    FAIL() << "no error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("target_alowed"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("a.ini"), std::string::npos) << e.what();
  }
  const std::string bad_section =
      write("b.ini", "[NavigatorParams]\nptg_ini = x.ini\n[Navigator]\n");
  EXPECT_THROW(loadNavConfig(robot, bad_section), std::exception);
}

TEST_F(NavTempIni, PathsAreRelativeToTheFileAndRulesAreChecked) {
  const std::string robot = kConfig + "/dune-kinect.ini";
  const NavConfig c = loadNavConfig(
      robot, write("n.ini", "[NavigatorParams]\nptg_ini = sub/ptg.ini\nptg_cache_dir = cache\n"));
  EXPECT_EQ(fs::path(c.ptg_ini), (dir_ / "sub/ptg.ini").lexically_normal());
  EXPECT_EQ(fs::path(c.ptg_cache_dir), (dir_ / "cache").lexically_normal());
  try {
    loadNavConfig(
        robot,
        write("t.ini", "[NavigatorParams]\nptg_ini = p.ini\n[RobotBodyParams]\ntrack_m = 0.9\n"));
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("RobotBodyParams.track_m = 0.9"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(loadNavConfig(robot, write("e.ini", "[LoopParams]\nseed = 2\n")),
               std::invalid_argument);  // no ptg_ini
  EXPECT_THROW(loadNavConfig(robot, (dir_ / "missing.ini").string()), std::runtime_error);
}

}  // namespace
}  // namespace upd::nav
