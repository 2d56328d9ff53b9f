// `upd render DIR` and `upd view` on a playback output folder, as a user runs them: a short
// simulated run of the mixed world (12 frames at 160 x 120) played back with --ply, then drawn
// and read back by its pixels. The map in the zeta colouring is mostly the green of planes with
// the blue of the obstacles' edges; in the label colouring the obstacles are red; the robot's
// box is orange; bad input is one line, exit 1 or 2, no file.
#include "image_colours.h"
#include "run_upd.h"
#include "temp_dir.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

namespace upd {
namespace {

namespace fs = std::filesystem;
using test::CmdResult;
using test::countColours;
using test::loadPng;
using test::runUpd;
using test::TempDir;

const std::string kConfigDir = std::string(UPD_SOURCE_DIR) + "/config/";

class ViewTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("view");
    const std::string rawlog = dir_->file("mixed.rawlog");
    const CmdResult s = runUpd("simulate --world mixed --config " + kConfigDir + "sim-long-run.ini --frames 12 --output " + rawlog);
    ASSERT_EQ(s.exit_code, 0) << s.output;
    const CmdResult p = runUpd("playback " + rawlog + " --config " + kConfigDir + "dune-kinect-realtime.ini --poses " +
                               dir_->file("mixed.gt.tum") + " --output " + dir_->file("out") + " --ply --quiet");
    ASSERT_EQ(p.exit_code, 0) << p.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static TempDir* dir_;
};
TempDir* ViewTest::dir_ = nullptr;

TEST_F(ViewTest, RenderOfAFolderShowsTheMapTheObstaclesAndTheRobot) {
  const std::string zeta = dir_->file("zeta.png"), label = dir_->file("label.png");
  CmdResult r = runUpd("render " + dir_->file("out") + " --output " + zeta + " --size 800x600");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("12 path points, 000011.ply"), std::string::npos) << r.output;
  const test::Counts z = countColours(loadPng(zeta), 800 - 170, 40);
  EXPECT_GT(z.green, 20000u) << "the ground: planes";
  EXPECT_GT(z.blue, 1000u) << "the rocks' and steps' edges";
  EXPECT_GT(z.green, 3 * z.blue);
  EXPECT_GT(z.orange, 100u) << "the robot";

  r = runUpd("render " + dir_->file("out") + " --output " + label + " --size 800x600 --color label --map octree");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const test::Counts l = countColours(loadPng(label), 800 - 170, 40);
  EXPECT_GT(l.green, 10000u) << "traversable voxels";
  EXPECT_GT(l.red, 1000u) << "the obstacles' voxels";
  EXPECT_LT(l.blue, 50u) << "no zeta colours in the label view";
}

TEST(ViewInput, RenderOfABadFolderIsOneLineAndNoFile) {
  const TempDir empty("empty");
  const std::string out = empty.file("bad.png");
  struct Case {
    std::string args;
    int exit_code;
  };
  for (const Case& c : {Case{"render " + empty.path().string() + " --output " + out, 1},
                        Case{"render " + empty.path().string() + " --output " + out + " --map voxels", 2}}) {
    const CmdResult r = runUpd(c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << c.args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}

}  // namespace
}  // namespace upd
