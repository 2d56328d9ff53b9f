// Reading a PNG back and counting its pixels by colour: how the figure and viewer tests check
// what a picture shows (the zeta map's green and blue, the label map's red).
#pragma once

#include <mrpt/img/CImage.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <string>

namespace upd::test {

struct Counts {
  std::size_t green = 0, blue = 0, cool = 0, red = 0, orange = 0, non_white = 0;
};

inline bool isGreen(const mrpt::img::TColor& c) { return c.G > c.R + 60 && c.G > c.B + 30; }
inline bool isBlue(const mrpt::img::TColor& c) { return c.B > c.G + 60 && c.B > c.R + 100; }
/// The zeta map's lower half, teal (zeta ~ 0.85) to blue (sqrt(2)/2): a discontinuity.
inline bool isTealOrBlue(const mrpt::img::TColor& c) { return c.B + 10 > c.G && c.B > c.R + 80; }
inline bool isRed(const mrpt::img::TColor& c) { return c.R > c.G + 100 && c.R > c.B + 100; }
/// The robot's box (245, 130, 20), lit.
inline bool isOrange(const mrpt::img::TColor& c) {
  return c.R > 150 && c.G > c.B + 40 && c.R > c.G + 40 && c.G > 60;
}

inline mrpt::img::TColor pixel(const mrpt::img::CImage& img, int x, int y) {
  const auto* p = img.ptr<std::uint8_t>(x, y);
  if (img.getChannelsOrder() == "BGR") return {p[2], p[1], p[0]};
  return {p[0], p[1], p[2]};
}

/// Counts over the columns [0, x_end) and rows [y_begin, height).
inline Counts countColours(const mrpt::img::CImage& img, int x_end, int y_begin = 0) {
  Counts n;
  for (int y = y_begin; y < int(img.getHeight()); ++y) {
    for (int x = 0; x < x_end; ++x) {
      const auto c = pixel(img, x, y);
      n.green += isGreen(c);
      n.blue += isBlue(c);
      n.cool += isTealOrBlue(c);
      n.red += isRed(c);
      n.orange += isOrange(c);
      n.non_white += c.R < 240 || c.G < 240 || c.B < 240;
    }
  }
  return n;
}

inline mrpt::img::CImage loadPng(const std::string& path) {
  mrpt::img::CImage img;
  EXPECT_TRUE(img.loadFromFile(path)) << path;
  return img;
}

}  // namespace upd::test
