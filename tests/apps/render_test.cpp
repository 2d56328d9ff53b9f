// `upd render` and `upd histogram` as a user runs them: the generated corner (a floor meeting a
// wall) scored at d_m = 0.1 m, drawn headless and read back. The pictures are checked by their pixels: the
// floor and wall in the zeta map's green, the corner's edge in its blue, the colour bar from
// green (top, zeta = 1) to blue (bottom, zeta = sqrt(2)/2); bad input writes no file.
#include "image_colours.h"
#include "run_upd.h"
#include "temp_dir.h"

#include <mrpt/img/CImage.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

namespace upd {
namespace {

using test::CmdResult;
using test::runUpd;
using test::TempDir;

using test::Counts;
using test::countColours;
using test::isBlue;
using test::isGreen;
using test::loadPng;
using test::pixel;

class RenderTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir("render");
    const CmdResult s = runUpd("scene corner --output " + dir_->file("corner.ply"));
    ASSERT_EQ(s.exit_code, 0) << s.output;
    const CmdResult a = runUpd("analyze " + dir_->file("corner.ply") + " --radius-m 0.1 --output " + dir_->file("scored.ply"));
    ASSERT_EQ(a.exit_code, 0) << a.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static TempDir* dir_;
};
TempDir* RenderTest::dir_ = nullptr;

TEST_F(RenderTest, ZetaFigureShowsPlanesGreenTheEdgeBlueAndAColourBar) {
  const std::string png = dir_->file("zeta.png");
  const CmdResult r = runUpd("render " + dir_->file("scored.ply") + " --output " + png + " --size 800x600");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const mrpt::img::CImage img = loadPng(png);
  ASSERT_EQ(img.getWidth(), 800u);
  ASSERT_EQ(img.getHeight(), 600u);
  const Counts view = countColours(img, 800 - 170);
  EXPECT_GT(view.green, 20000u) << "the floor and the wall";
  // At d_m = 0.1 m the edge's zeta is about 0.88 (the PCA normals over 0.1 m round it): teal.
  EXPECT_GT(view.cool, 300u) << "the corner's edge";
  EXPECT_GT(view.green, 3 * view.cool) << "at d_m = 0.1 m most of the corner is plane";
  // The bar: column x = W - 170 + 20 + 13, from y = 60 (zeta = 1) to y = H - 60 (sqrt(2)/2).
  EXPECT_TRUE(isGreen(pixel(img, 800 - 137, 63)));
  EXPECT_TRUE(isBlue(pixel(img, 800 - 137, 600 - 63)));
}

TEST_F(RenderTest, RawCloudIsScoredOnTheFlyAndLabelsAndNormalsDraw) {
  const std::string png = dir_->file("label.png");
  const CmdResult r = runUpd("render " + dir_->file("corner.ply") + " --output " + png +
                             " --color label --normals --size 640x480 --view-from 3,2,2.5 --look-at 0.5,0.5,0.2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const mrpt::img::CImage img = loadPng(png);
  EXPECT_EQ(img.getWidth(), 640u);
  const Counts view = countColours(img, 640 - 170);
  EXPECT_GT(view.green, 3000u) << "traversable floor";
  EXPECT_GT(view.red, 100u) << "the wall and the edge are not traversable";
}

TEST_F(RenderTest, HistogramIsAPlotOfTheRequestedSize) {
  const std::string png = dir_->file("hist.png");
  const CmdResult r = runUpd("histogram " + dir_->file("corner.ply") + " --radii 0.1,0.5 --output " + png +
                             " --size 900x500");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const mrpt::img::CImage img = loadPng(png);
  ASSERT_EQ(img.getWidth(), 900u);
  ASSERT_EQ(img.getHeight(), 500u);
  const Counts n = countColours(img, 900);
  EXPECT_GT(n.non_white, 5000u) << "axes, grid, text and lines";
  EXPECT_GT(n.blue, 200u) << "the first series (blue)";
}

TEST_F(RenderTest, BadInputIsOneLineAndNoFile) {
  struct Case {
    std::string args;
    int exit_code;
  };
  const std::string out = dir_->file("bad.png");
  const std::string scored = dir_->file("scored.ply");
  for (const Case& c : {Case{"render " + dir_->file("missing.ply") + " --output " + out, 1},
                        Case{"render " + scored + " --output " + out + " --size 12", 2},
                        Case{"render " + scored + " --output " + out + " --color rainbow", 2},
                        Case{"render " + scored + " --output " + out + " --size 100x100", 1},
                        Case{"histogram " + scored + " --output " + out + " --radii 0.1,x", 2},
                        Case{"histogram " + dir_->file("missing.ply") + " --output " + out + " --radii 0.5", 1}}) {
    const CmdResult r = runUpd(c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.args << "\n" << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << c.args << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(out)) << c.args;
  }
}

}  // namespace
}  // namespace upd
