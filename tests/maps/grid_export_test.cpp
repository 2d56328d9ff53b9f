// The grid's outputs: ROS map_server PGM + YAML, colour PNG with legend, and atomic writes (the
// MRPT occupancy grid is tested with the bridge: tests/mrpt_bridge/occupancy_grid_test.cpp).
#include "maps/frames.h"
#include "upd/maps/grid_export.h"
#include "upd/maps/grid_fusion.h"
#include "upd/io/ros_map.h"

#include <gtest/gtest.h>
#include <mrpt/img/CImage.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string>


using upd::maps::GridParams;
using upd::maps::TraversabilityGrid;
using upd::test::kFreeX;
using upd::test::kFreeY;
using upd::test::kObsX;
using upd::test::kObsY;
using upd::test::twoCellGrid;
using upd::test::TempDir;

namespace {

struct Pgm {
  int width = 0, height = 0, maxval = 0;
  std::string pixels;
  unsigned char at(int col, int row) const {
    return static_cast<unsigned char>(pixels[static_cast<std::size_t>(row) * width + col]);
  }
};

Pgm readPgm(const std::string& path) {
  const std::string data = upd::test::readFileBytes(path);
  std::istringstream in(data);
  std::string magic;
  Pgm p;
  in >> magic >> p.width >> p.height >> p.maxval;
  EXPECT_EQ(magic, "P5");
  in.get();  // the single whitespace before the raster
  p.pixels = data.substr(static_cast<std::size_t>(in.tellg()));
  EXPECT_EQ(p.pixels.size(), static_cast<std::size_t>(p.width) * p.height);
  return p;
}

std::string yamlValue(const std::string& yaml, const std::string& key) {
  std::istringstream in(yaml);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key + ": ", 0) == 0) return line.substr(key.size() + 2);
  }
  return {};
}

std::array<int, 3> rgbAt(const mrpt::img::CImage& img, int col, int row) {
  const bool bgr = img.getChannelsOrder() == "BGR";
  const int r = img.at<uint8_t>(col, row, bgr ? 2 : 0);
  const int g = img.at<uint8_t>(col, row, 1);
  const int b = img.at<uint8_t>(col, row, bgr ? 0 : 2);
  return {r, g, b};
}

bool noTemporaryFiles(const TempDir& dir) {
  for (const auto& name : dir.listing()) {
    if (name.find(".tmp") != std::string::npos) return false;
  }
  return true;
}

}  // namespace

TEST(RosMap, PgmAndYamlFollowMapServerFormatAndOrientation) {
  const TraversabilityGrid g = twoCellGrid();
  TempDir dir("rosmap");
  upd::maps::writeRosMap(g, dir.file("trav"));
  ASSERT_TRUE(std::filesystem::exists(dir.file("trav.pgm")));
  ASSERT_TRUE(std::filesystem::exists(dir.file("trav.yaml")));
  EXPECT_TRUE(noTemporaryFiles(dir));
  EXPECT_EQ(dir.listing().size(), 2u);

  const std::string yaml = upd::test::readFileBytes(dir.file("trav.yaml"));
  EXPECT_EQ(yamlValue(yaml, "image"), "trav.pgm");
  EXPECT_EQ(yamlValue(yaml, "resolution"), "0.1");
  EXPECT_EQ(yamlValue(yaml, "negate"), "0");
  EXPECT_EQ(yamlValue(yaml, "occupied_thresh"), "0.65");
  EXPECT_EQ(yamlValue(yaml, "free_thresh"), "0.196");
  EXPECT_EQ(yamlValue(yaml, "mode"), "trinary");
  double ox = 0, oy = 0, oz = 1;
  ASSERT_EQ(std::sscanf(yamlValue(yaml, "origin").c_str(), "[%lf, %lf, %lf]", &ox, &oy, &oz), 3)
      << yaml;
  EXPECT_NEAR(ox, -3.0, 1e-9);
  EXPECT_NEAR(oy, -6.0, 1e-9);
  EXPECT_EQ(oz, 0.0);

  const Pgm pgm = readPgm(dir.file("trav.pgm"));
  ASSERT_EQ(pgm.width, 80);
  ASSERT_EQ(pgm.height, 80);
  EXPECT_EQ(pgm.maxval, 255);
  // map_server: pixel (col, row) is at x = origin_x + (col + 0.5) res,
  // y = origin_y + (height - row - 0.5) res (row 0 is the top).
  auto pixelOf = [&](double x, double y) {
    const int col = static_cast<int>(std::floor((x - ox) / 0.1));
    const int row = pgm.height - 1 - static_cast<int>(std::floor((y - oy) / 0.1));
    return pgm.at(col, row);
  };
  EXPECT_EQ(pixelOf(kObsX, kObsY), upd::io::kRosOccupied);
  EXPECT_EQ(pixelOf(kFreeX, kFreeY), upd::io::kRosFree);
  int occupied = 0, free = 0, unknown = 0;
  for (unsigned char v : pgm.pixels) {
    occupied += v == upd::io::kRosOccupied;
    free += v == upd::io::kRosFree;
    unknown += v == upd::io::kRosUnknown;
  }
  EXPECT_EQ(occupied, 1);
  EXPECT_EQ(free, 1);
  EXPECT_EQ(unknown, 80 * 80 - 2);
  // The obstacle is in the upper half of the image (it is north of the window centre) and
  // the free cell in the lower half: the image is not flipped.
  EXPECT_EQ(pgm.at(53, 32), upd::io::kRosOccupied);  // col (2.35 + 3) / 0.1, row 79 - 47
  EXPECT_EQ(pgm.at(35, 50), upd::io::kRosFree);      // col (0.55 + 3) / 0.1, row 79 - 29
}

TEST(ColourPng, ReadableWithColoursAndLegend) {
  const TraversabilityGrid g = twoCellGrid();
  TempDir dir("png");
  const std::string path = dir.file("trav.png");
  const auto layout = upd::maps::writeColourPng(g, path);
  EXPECT_TRUE(noTemporaryFiles(dir));
  mrpt::img::CImage img;  // decodes with OpenCV's cv::imread
  ASSERT_TRUE(img.loadFromFile(path));
  ASSERT_TRUE(img.isColor());
  EXPECT_EQ(static_cast<int>(img.getWidth()), layout.image_width_px);
  EXPECT_EQ(static_cast<int>(img.getHeight()), layout.image_height_px);
  EXPECT_EQ(layout.pixels_per_cell, 7);  // 600 px / 80 cells
  EXPECT_EQ(layout.map_width_px, 80 * 7);
  EXPECT_GT(layout.image_height_px, layout.map_height_px + 40);  // room for the legend

  const int ppc = layout.pixels_per_cell;
  auto pixelOf = [&](double x, double y) {
    int cx, cy;
    EXPECT_TRUE(g.cellIndex(x, y, cx, cy));
    return rgbAt(img, cx * ppc + ppc / 2, (g.sizeY() - 1 - cy) * ppc + ppc / 2);
  };
  auto expected = [&](double x, double y) {
    const auto c =
        upd::maps::traversabilityColourRgb(upd::maps::probabilityNonTraversable(g, x, y));
    return std::array<int, 3>{c[0], c[1], c[2]};
  };
  const auto obstacle = pixelOf(kObsX, kObsY);
  EXPECT_EQ(obstacle, expected(kObsX, kObsY));
  EXPECT_GT(obstacle[0], 200);  // red
  EXPECT_LT(obstacle[1], 60);
  const auto free = pixelOf(kFreeX, kFreeY);  // p = 0.23: green with some yellow
  EXPECT_EQ(free, expected(kFreeX, kFreeY));
  EXPECT_GT(free[1], 200);
  EXPECT_LT(free[0], 128);
  const auto unknown = pixelOf(-2.0, -5.0);
  EXPECT_EQ(unknown, (std::array<int, 3>{128, 128, 128}));

  // The legend: below the map, holds the colour bar (green at its left, red at its right),
  // the grey swatch and text.
  const int bar_row = layout.legend_top_px + 16;
  const auto left = rgbAt(img, 12, bar_row);
  const auto right = rgbAt(img, 207, bar_row);
  EXPECT_GT(left[1], 200);
  EXPECT_LT(left[0], 40);
  EXPECT_GT(right[0], 200);
  EXPECT_LT(right[1], 40);
  int dark = 0, grey = 0;
  for (int row = layout.legend_top_px; row < layout.image_height_px; ++row) {
    for (int col = 0; col < layout.image_width_px; ++col) {
      const auto c = rgbAt(img, col, row);
      dark += (c[0] < 80 && c[1] < 80 && c[2] < 80) ? 1 : 0;
      grey += (c == std::array<int, 3>{128, 128, 128}) ? 1 : 0;
    }
  }
  EXPECT_GT(dark, 300);  // text, frames and the scale bar
  EXPECT_GT(grey, 100);  // the unknown swatch
}

TEST(ColourPng, SmallGridsKeepTheLegendReadable) {
  GridParams gp;
  gp.extent_m = 1.0;
  gp.follow_robot = false;
  TraversabilityGrid g(gp);
  TempDir dir("png_small");
  const auto layout = upd::maps::writeColourPng(g, dir.file("small.png"), 3);
  EXPECT_EQ(layout.map_width_px, 30);
  EXPECT_GE(layout.image_width_px, 400);
  mrpt::img::CImage img;
  ASSERT_TRUE(img.loadFromFile(dir.file("small.png")));
  EXPECT_EQ(rgbAt(img, 15, 15), (std::array<int, 3>{128, 128, 128}));
}

TEST(ColourScale, GreenYellowRedGrey) {
  using upd::maps::traversabilityColourRgb;
  EXPECT_EQ(traversabilityColourRgb(0.f), (std::array<std::uint8_t, 3>{0, 255, 0}));
  EXPECT_EQ(traversabilityColourRgb(0.5f), (std::array<std::uint8_t, 3>{255, 255, 0}));
  EXPECT_EQ(traversabilityColourRgb(1.f), (std::array<std::uint8_t, 3>{255, 0, 0}));
  EXPECT_EQ(traversabilityColourRgb(NAN), upd::maps::kUnknownColourRgb);
}

TEST(GridExport, WritingIntoAMissingDirectoryFailsNamingThePath) {
  const TraversabilityGrid g = twoCellGrid();
  TempDir dir("missing");
  const std::string missing = dir.file("no_such_dir");
  auto expectFailure = [&](auto&& write, const std::string& target) {
    try {
      write();
      ADD_FAILURE() << "no exception for " << target;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(target), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << "one line";
    }
  };
  expectFailure([&] { upd::maps::writeColourPng(g, missing + "/map.png"); }, missing + "/map.png");
  expectFailure([&] { upd::maps::writeRosMap(g, missing + "/map"); }, missing + "/map.pgm");
  EXPECT_FALSE(std::filesystem::exists(missing));
  EXPECT_TRUE(dir.listing().empty());
}

TEST(GridExport, RewritingReplacesTheFileAtomically) {
  TraversabilityGrid g = twoCellGrid();
  TempDir dir("rewrite");
  upd::maps::writeRosMap(g, dir.file("m"));
  const std::string first = upd::test::readFileBytes(dir.file("m.pgm"));
  g.clear();
  upd::maps::writeRosMap(g, dir.file("m"));
  const std::string second = upd::test::readFileBytes(dir.file("m.pgm"));
  EXPECT_EQ(first.size(), second.size());
  EXPECT_NE(first, second);
  EXPECT_EQ(second.find(static_cast<char>(upd::io::kRosOccupied), 10), std::string::npos);
  EXPECT_EQ(dir.listing().size(), 2u);
}
