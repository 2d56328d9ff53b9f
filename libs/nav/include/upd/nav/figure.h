// Figures of scored clouds, drawn headless: a 3D view of a cloud coloured by zeta (or label,
// cost, slope, height) with a colour bar, rendered off-screen by MRPT's CFBORender (Mesa EGL,
// no display needed), and the distribution of zeta at several d_m as a line plot. Data in,
// PNG out; every function throws std::runtime_error / std::invalid_argument with a one-line
// message on bad input and writes its PNG through a temporary file renamed into place.
//
// Colour maps (fixed, so figures compare across runs):
// - zeta: t = (1 - zeta) / (1 - sqrt(2)/2), clamped to [0, 1]; t = 0 (zeta = 1, a plane) is
//   green (40, 170, 60), t = 1 (zeta <= sqrt(2)/2, a right-angle discontinuity) is blue
//   (30, 60, 220), through teal; invalid (NaN) zeta is grey.
// - label: traversable green, non-traversable red, unknown grey.
// - cost: 0 green, 0.5 yellow, 1 red.
// - rgb: the cloud's own colour (red green blue of the PLY or PCD), grey when it has none.
// - slope: angle between the normal and up, 0 to 45 degrees (and beyond), and height: the
//   cloud's range along up; both on a blue - cyan - yellow - red ramp.
#pragma once

#include "upd/core/point_cloud.h"

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace upd::nav {

enum class FigureColor { Zeta, Label, Cost, Slope, Height, Rgb };

/// "zeta", "label", "cost", "slope", "height" or "rgb" (the camera's colour, grey where the
/// cloud has none); anything else throws std::invalid_argument.
FigureColor parseFigureColor(const std::string& name);

/// A scored cloud as the figures need it: positions, unit normals, zeta, label and cost per
/// point (all of one size).
struct ScoredCloud {
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
  std::vector<float> zeta, cost;
  std::vector<core::Label> label;
  std::vector<std::array<std::uint8_t, 3>> rgb;  ///< the camera's colour; empty when none
  std::size_t size() const { return points.size(); }
};

/// Reads a scored PLY (the file `upd analyze --output` writes: it has scalar_zeta), or reads a
/// raw cloud (.pcd, .ply, .xyz) and scores it with the default pipeline parameters and this up
/// vector. Points with a non-finite position are dropped. Throws when the file is missing or bad.
ScoredCloud loadScoredCloud(const std::string& path, const Eigen::Vector3f& up = Eigen::Vector3f::UnitZ());

/// The colour of zeta on the documented map (see the header comment).
struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};
Rgb zetaColor(float zeta);

struct RenderOptions {
  FigureColor color = FigureColor::Zeta;
  bool normals = false;           ///< draw normals as short segments (at most ~1500 of them)
  std::optional<Eigen::Vector3f> view_from, look_at;  ///< camera, in the cloud frame
  Eigen::Vector3f up{0, 0, 1};    ///< the cloud's up vector
  int width = 1280, height = 900; ///< of the PNG, colour bar included
  float point_size = 4.0f;        ///< [pixels]
  std::string title;              ///< drawn at the top left when not empty
};

/// Renders the cloud to a PNG. Default camera: looking at the centre of the bounding box from
/// 35 degrees above, far enough to see all of it, from behind (-x) and to the side, or from the
/// diagonal that sees the front of the most surfaces (normals face the sensor).
void renderFigure(const ScoredCloud& cloud, const RenderOptions& options, const std::string& png);

/// One distribution of zeta: the values scored at radius d_m.
struct ZetaSeries {
  double radius_m = 0;
  std::vector<float> zeta;
};

struct HistogramOptions {
  int width = 1000, height = 620;
  /// Bins over [lo, 1]: lo = min(0.70, the 1st percentile of zeta rounded down to 0.05); the
  /// few values below lo are counted in the first bin.
  int bins = 30;
  std::string title;   ///< drawn above the plot when not empty
};

/// Draws the share of points per zeta bin (percent), one line per series, with axes, ticks,
/// labels and a legend. Throws for no series, a series without finite zeta, or a bad size.
void drawZetaHistogram(const std::vector<ZetaSeries>& series, const HistogramOptions& options,
                       const std::string& png);

}  // namespace upd::nav
