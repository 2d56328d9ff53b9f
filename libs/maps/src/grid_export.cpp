#include "upd/maps/grid_export.h"

#include "upd/io/atomic_file.h"
#include "upd/io/ros_map.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace upd::maps {

std::array<std::uint8_t, 3> traversabilityColourRgb(float p_nontrav) {
  if (std::isnan(p_nontrav)) return kUnknownColourRgb;
  const float p = std::clamp(p_nontrav, 0.f, 1.f);
  // Green (0) -> yellow (0.5) -> red (1): red rises over the first half, green falls over the
  // second.
  const auto r = static_cast<std::uint8_t>(std::lround(255.f * std::min(1.f, 2.f * p)));
  const auto g = static_cast<std::uint8_t>(std::lround(255.f * std::min(1.f, 2.f * (1.f - p))));
  return {r, g, 0};
}

namespace {

cv::Scalar bgr(const std::array<std::uint8_t, 3>& rgb) {
  return cv::Scalar(rgb[2], rgb[1], rgb[0]);
}

// The longest "nice" length (1, 2 or 5 x 10^k metres) that fits in max_px.
double scaleBarLength(double metres_per_px, int max_px) {
  const double max_m = metres_per_px * max_px;
  double best = 0;
  for (double decade = 1e-3; decade <= 1e6; decade *= 10) {
    for (double m : {1.0, 2.0, 5.0}) {
      if (m * decade <= max_m) best = m * decade;
    }
  }
  return best;
}

std::string formatMetres(double m) {
  std::ostringstream os;
  os << std::setprecision(3) << m << " m";
  return os.str();
}

void drawLegend(cv::Mat& img, int top, double cell_size_m, int pixels_per_cell) {
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double fs = 0.42;
  const cv::Scalar black(0, 0, 0);
  const int bar_x = 10, bar_w = 200, bar_h = 16;
  const int y0 = top + 8;
  // Colour bar: probability of being non-traversable, 0 at the left.
  for (int i = 0; i < bar_w; ++i) {
    const float p = static_cast<float>(i) / static_cast<float>(bar_w - 1);
    cv::line(img, {bar_x + i, y0}, {bar_x + i, y0 + bar_h - 1}, bgr(traversabilityColourRgb(p)));
  }
  cv::rectangle(img, {bar_x - 1, y0 - 1}, {bar_x + bar_w, y0 + bar_h}, black);
  int baseline = 0;
  cv::putText(img, "traversable", {bar_x, y0 + bar_h + 14}, font, fs, black, 1, cv::LINE_AA);
  const cv::Size nt = cv::getTextSize("non-traversable", font, fs, 1, &baseline);
  cv::putText(img, "non-traversable", {bar_x + bar_w - nt.width, y0 + bar_h + 14}, font, fs, black,
              1, cv::LINE_AA);
  // Unknown swatch.
  const int sw_x = bar_x + bar_w + 30;
  cv::rectangle(img, {sw_x, y0}, {sw_x + bar_h - 1, y0 + bar_h - 1}, bgr(kUnknownColourRgb),
                cv::FILLED);
  cv::rectangle(img, {sw_x - 1, y0 - 1}, {sw_x + bar_h, y0 + bar_h}, black);
  cv::putText(img, "unknown", {sw_x + bar_h + 6, y0 + bar_h - 3}, font, fs, black, 1, cv::LINE_AA);
  // Cell size and scale bar.
  const int y1 = y0 + bar_h + 34;
  std::ostringstream cell;
  cell << "cell " << std::setprecision(3) << cell_size_m << " m";
  cv::putText(img, cell.str(), {bar_x, y1}, font, fs, black, 1, cv::LINE_AA);
  const double metres_per_px = cell_size_m / pixels_per_cell;
  const double bar_m = scaleBarLength(metres_per_px, 150);
  if (bar_m > 0) {
    const int len = static_cast<int>(std::lround(bar_m / metres_per_px));
    const int sx = bar_x + 110;
    cv::line(img, {sx, y1 - 4}, {sx + len, y1 - 4}, black, 2);
    cv::line(img, {sx, y1 - 9}, {sx, y1 + 1}, black, 1);
    cv::line(img, {sx + len, y1 - 9}, {sx + len, y1 + 1}, black, 1);
    cv::putText(img, formatMetres(bar_m), {sx + len + 8, y1}, font, fs, black, 1, cv::LINE_AA);
  }
}

void writeBytes(const std::string& path, const void* data, std::size_t n) {
  io::writeFileAtomically(path, [&](std::ostream& out) {
    out.write(static_cast<const char*>(data), static_cast<std::streamsize>(n));
  });
}

}  // namespace

ColourPngLayout writeColourPng(const TraversabilityGrid& grid, const std::string& path,
                               int pixels_per_cell) {
  if (pixels_per_cell < 0) {
    throw std::invalid_argument(
        "writeColourPng: pixels_per_cell = " + std::to_string(pixels_per_cell) + ": must be >= 0");
  }
  ColourPngLayout L;
  const int side = std::max(grid.sizeX(), grid.sizeY());
  L.pixels_per_cell = pixels_per_cell > 0 ? pixels_per_cell : std::clamp(600 / side, 1, 8);
  L.map_width_px = grid.sizeX() * L.pixels_per_cell;
  L.map_height_px = grid.sizeY() * L.pixels_per_cell;
  L.legend_top_px = L.map_height_px;
  L.image_width_px = std::max(L.map_width_px, 420);  // room for the legend's text
  L.image_height_px = L.map_height_px + 84;

  cv::Mat img(L.image_height_px, L.image_width_px, CV_8UC3, cv::Scalar(255, 255, 255));
  const int ppc = L.pixels_per_cell;
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    const int row0 = (grid.sizeY() - 1 - cy) * ppc;  // north up
    for (int cx = 0; cx < grid.sizeX(); ++cx) {
      const auto rgb = traversabilityColourRgb(probabilityOf(grid.at(cx, cy), grid.params()));
      for (int r = row0; r < row0 + ppc; ++r) {
        auto* px = img.ptr<cv::Vec3b>(r) + cx * ppc;
        for (int k = 0; k < ppc; ++k) px[k] = cv::Vec3b(rgb[2], rgb[1], rgb[0]);
      }
    }
  }
  drawLegend(img, L.legend_top_px, grid.cellSize(), ppc);

  std::vector<uchar> png;
  if (!cv::imencode(".png", img, png)) {
    throw std::runtime_error("cannot write '" + path + "': PNG encoding failed");
  }
  writeBytes(path, png.data(), png.size());
  return L;
}

void writeRosMap(const TraversabilityGrid& grid, const std::string& path_without_ext) {
  io::RosMap map;
  map.resolution_m = grid.cellSize();
  map.origin_xy = {grid.xMin(), grid.yMin()};
  map.width = grid.sizeX();
  map.height = grid.sizeY();
  map.labels.resize(static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height));
  for (int cy = 0; cy < map.height; ++cy) {
    for (int cx = 0; cx < map.width; ++cx) {
      map.labels[static_cast<std::size_t>(cy) * map.width + cx] =
          labelOf(grid.at(cx, cy), grid.params());
    }
  }
  io::writeRosMap(map, path_without_ext + ".yaml");
}

void writeRosCostMap(const TraversabilityGrid& grid, const std::string& path_without_ext) {
  io::RosScaleMap map;
  map.resolution_m = grid.cellSize();
  map.origin_xy = {grid.xMin(), grid.yMin()};
  map.width = grid.sizeX();
  map.height = grid.sizeY();
  map.p_occupied.resize(static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height));
  for (int cy = 0; cy < map.height; ++cy) {
    for (int cx = 0; cx < map.width; ++cx) {
      map.p_occupied[static_cast<std::size_t>(cy) * map.width + cx] =
          probabilityOf(grid.at(cx, cy), grid.params());
    }
  }
  io::writeRosScaleMap(map, path_without_ext + ".yaml");
}

}  // namespace upd::maps
