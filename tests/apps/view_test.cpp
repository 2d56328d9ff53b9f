// `upd render DIR` and `upd view` on a playback output folder, as a user runs them: a short
// simulated run of the mixed world (12 frames at 160 x 120) played back with --ply, then drawn
// and read back by its pixels. The map in the zeta colouring is mostly the green of planes with
// the blue of the obstacles' edges; in the label colouring the obstacles are red; the robot's
// box is orange; bad input is one line, exit 1 or 2, no file. The viewer runs in a virtual X
// server (Xvfb, Mesa's software GL) and saves what its window shows (--screenshot), after the
// key that switches to the label colouring (--keys l).
#include "image_colours.h"
#include "run_upd.h"
#include "temp_dir.h"
#include "xvfb_server.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
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

TEST_F(ViewTest, ViewerWindowShowsZetaThenLabelsAfterTheKey) {
  const test::XvfbServer x;
  if (!x.available()) GTEST_SKIP() << "Xvfb is not installed: the viewer's window is not tested";
  const std::string env = "DISPLAY=" + x.display() + " ";
  const std::string zeta = dir_->file("view-zeta.png"), label = dir_->file("view-label.png");
  const std::string view = "view " + dir_->file("out") + " --size 900x640 --exit-after --screenshot ";
  CmdResult r = test::runCommand(env + UPD_BINARY + " " + view + zeta);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const mrpt::img::CImage zimg = loadPng(zeta);
  ASSERT_EQ(zimg.getWidth(), 900u);
  ASSERT_EQ(zimg.getHeight(), 640u);
  const test::Counts z = countColours(zimg, 900 - 170, 40);
  EXPECT_GT(z.green, 20000u) << "the ground: planes";
  EXPECT_GT(z.blue, 1000u) << "the rocks' and steps' edges";
  EXPECT_GT(z.green, 3 * z.blue) << "most of the ground is plane";
  EXPECT_GT(20 * z.blue, z.green) << "the edges: over 5 % of the plane's pixels";
  EXPECT_GT(z.orange, 100u) << "the robot";
  EXPECT_GT(z.non_white, z.green + z.blue + z.orange) << "the help text and the path";
  // The colour bar at the right: green at the top (zeta = 1), blue at the bottom.
  EXPECT_TRUE(test::isGreen(test::pixel(zimg, 900 - 137, 63)));
  EXPECT_TRUE(test::isBlue(test::pixel(zimg, 900 - 137, 640 - 63)));

  r = test::runCommand(env + UPD_BINARY + " " + view + label + " --keys l");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const test::Counts l = countColours(loadPng(label), 900 - 170, 40);
  EXPECT_GT(l.green, 20000u) << "traversable ground";
  EXPECT_GT(l.red, 1000u) << "the obstacles";
  EXPECT_GT(10 * l.red, l.green) << "the obstacles' bands: over 10 % of the traversable pixels";
  EXPECT_LT(l.blue, 50u) << "no zeta colours after the key";
}

TEST_F(ViewTest, MapOtDrawsByLabelAndTruncatedIsOneLineAndNoFile) {
  // map.ot (OctoMap's ColorOcTree) whole draws; cut short it is an error, not a partial map.
  const std::string whole = dir_->file("out/map.ot");
  const std::string png = dir_->file("map_ot.png");
  const CmdResult ok = runUpd("render " + whole + " --output " + png + " --size 900x640");
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  // It holds no zeta, only the labels' colours: drawn by label unless asked, not all grey.
  EXPECT_NE(ok.output.find("drawn by label"), std::string::npos) << ok.output;
  const test::Counts c = countColours(loadPng(png), 900 - 170, 40);
  EXPECT_GT(c.green, 5000u) << "traversable ground";
  EXPECT_GT(c.red, 200u) << "the obstacles";
  const std::string bytes = test::readFileBytes(whole);
  for (const std::size_t keep : {bytes.size() / 2, bytes.size() - 3}) {
    const std::string cut = dir_->file("cut.ot");
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, keep);
    const std::string out = dir_->file("cut.png");
    const CmdResult r = runUpd("render " + cut + " --output " + out);
    EXPECT_EQ(r.exit_code, 1) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_NE(r.output.find(cut), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("truncated"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
  }
}

TEST(ViewInput, BadInputIsOneLineAndNoFile) {
  const TempDir empty("empty");
  const std::string out = empty.file("bad.png");
  struct Case {
    std::string args;
    int exit_code;
  };
  const std::string missing = empty.file("missing.ply");
  for (const Case& c : {Case{"render " + empty.path().string() + " --output " + out, 1},
                        Case{"render " + empty.path().string() + " --output " + out + " --map voxels", 2},
                        Case{"view " + missing + " --screenshot " + out, 1},
                        Case{"view " + empty.path().string() + " --screenshot " + out, 1},
                        Case{"view " + missing + " --color rainbow", 2}}) {
    const CmdResult r = runUpd(c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << c.args << "\n" << r.output;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
}

}  // namespace
}  // namespace upd
