// The pieces shared by the headless figures (figure_render.cpp, map_figure.cpp) and the
// interactive viewer (viewer.cpp): colour maps, the cloud turned upright, the cloud and its
// normals as MRPT objects, the default camera and the colour bar panel.
#pragma once

#include "upd/nav/figure.h"

#include <mrpt/img/CImage.h>
#include <mrpt/opengl/CCamera.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>

#include <Eigen/Core>

#include <vector>

namespace upd::nav::detail {

constexpr int kPanelWidth = 170;       ///< the colour bar's column at the right [px]
constexpr float kMaxSlopeDeg = 45.0f;  ///< top of the slope colour map

Rgb ramp(float t);  ///< blue - cyan - yellow - red over [0, 1]
Rgb costColor(float c);
Rgb labelColor(core::Label l);
Rgb slopeColor(float deg);
Rgb heightColor(float z, float lo, float hi);

/// A cloud rotated so that up is +z, and the extent of what is drawn (cloud, map, path).
struct Frame {
  std::vector<Eigen::Vector3f> p, n;
  Eigen::Matrix3f rot = Eigen::Matrix3f::Identity();
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = Eigen::Vector3f::Constant(-1e30f);
  bool empty() const { return !(lo.x() <= hi.x()); }
  void extend(const Eigen::Vector3f& q) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
};

Frame upright(const ScoredCloud& c, const Eigen::Vector3f& up);

/// The cloud's points coloured by mode (height over the frame's z range).
mrpt::opengl::CPointCloudColoured::Ptr cloudPoints(const ScoredCloud& c, const Frame& f, FigureColor mode,
                                                   float point_size);
/// Every k-th normal (at most ~1500) as a dark segment 4 % of the diagonal of the cloud's
/// points f.p long (a map may make the frame's box larger).
mrpt::opengl::CSetOfLines::Ptr normalLines(const Frame& f);

/// The default view: the frame's centre from elevation_deg above, from the diagonal that sees
/// the front of most normals, far enough to see it all; or --view-from / --look-at.
mrpt::opengl::CCamera camera(const Frame& f, const RenderOptions& o, double aspect,
                             double elevation_deg = 35.0);

/// The colour bar (or the label legend) of mode in a kPanelWidth-wide column starting at x
/// of an image height px tall; height's bar spans [z_lo, z_hi].
void drawBar(mrpt::img::CImage& img, int x, int height, FigureColor mode, float z_lo, float z_hi);

/// Renders scene off-screen (CFBORender) with camera(f, o, ..., elevation_deg), puts the colour
/// bar of o.color at the right and o.title at the top left, and writes the PNG atomically.
void renderToPng(mrpt::opengl::COpenGLScene& scene, const Frame& f, const RenderOptions& o,
                 double elevation_deg, const std::string& png);

}  // namespace upd::nav::detail
