// The colour maps, the camera and the colour bar shared by the figures and the viewer
// (figure_scene.h).
#include "figure_scene.h"

#include "upd/nav/scene_objects.h"

#include <mrpt/core/format.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_set>

namespace upd::nav::detail {

Rgb ramp(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  const float stops[4][3] = {{40, 60, 200}, {30, 180, 210}, {240, 210, 40}, {210, 40, 30}};
  const float s = t * 3.0f;
  const int i = std::min(2, int(s));
  const float u = s - float(i);
  auto mix = [&](int c) { return std::uint8_t(std::lround(stops[i][c] + (stops[i + 1][c] - stops[i][c]) * u)); };
  return {mix(0), mix(1), mix(2)};
}

Rgb costColor(float c) {  // green - yellow - red
  if (!(c == c)) return {150, 150, 150};
  c = std::clamp(c, 0.0f, 1.0f);
  if (c < 0.5f) return {std::uint8_t(40 + 400 * c), std::uint8_t(170 + 60 * c), 40};
  return {240, std::uint8_t(200 - 340 * (c - 0.5f)), 40};
}

Rgb labelColor(core::Label l) {
  if (l == core::Label::Traversable) return {40, 170, 60};
  if (l == core::Label::NonTraversable) return {210, 40, 30};
  return {150, 150, 150};
}

Rgb slopeColor(float deg) {
  if (!(deg == deg)) return {150, 150, 150};
  return ramp(deg / kMaxSlopeDeg);
}

Rgb heightColor(float z, float lo, float hi) {
  if (!(z == z)) return {150, 150, 150};
  return ramp(hi > lo ? (z - lo) / (hi - lo) : 0.0f);
}

Frame upright(const ScoredCloud& c, const Eigen::Vector3f& up) {
  if (!(up.norm() > 0)) throw std::invalid_argument("the up vector must not be zero");
  Frame f;
  f.rot = Eigen::Quaternionf::FromTwoVectors(up.normalized(), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  for (std::size_t i = 0; i < c.size(); ++i) {
    f.p.push_back(f.rot * c.points[i]);
    f.n.push_back(f.rot * c.normals[i]);
    f.extend(f.p.back());
  }
  return f;
}

namespace {

Rgb pointColor(const ScoredCloud& c, const Frame& f, std::size_t i, FigureColor mode) {
  switch (mode) {
    case FigureColor::Zeta: return zetaColor(c.zeta[i]);
    case FigureColor::Label: return labelColor(c.label[i]);
    case FigureColor::Cost: return costColor(c.cost[i]);
    case FigureColor::Slope: {
      if (!f.n[i].allFinite()) return {150, 150, 150};
      return slopeColor(std::acos(std::min(1.0f, std::abs(f.n[i].z()))) * 180.0f / float(M_PI));
    }
    case FigureColor::Height: return heightColor(f.p[i].z(), f.lo.z(), f.hi.z());
    case FigureColor::Rgb:
      if (c.rgb.size() != c.size()) return {150, 150, 150};
      return {c.rgb[i][0], c.rgb[i][1], c.rgb[i][2]};
  }
  return {};
}

// Behind (-x) and to the side, unless the surfaces face another way: of the four diagonal
// views, the first that sees the most of the normals' front sides (the pipeline orients normals
// towards the sensor), so a wall is not seen from its back.
float defaultAzimuth(const Frame& f, double elevation_deg) {
  const float candidates[] = {-140.0f, 140.0f, -40.0f, 40.0f};
  float best = candidates[0];
  double best_score = -1e300;
  for (float az : candidates) {
    const double a = az * M_PI / 180.0, e = elevation_deg * M_PI / 180.0;
    const Eigen::Vector3f d(float(std::cos(e) * std::cos(a)), float(std::cos(e) * std::sin(a)), float(std::sin(e)));
    double score = 0;
    for (const auto& n : f.n) if (n.allFinite()) score += n.dot(d);
    if (score > best_score + 1e-6 * f.n.size()) best = az, best_score = score;
  }
  return best;
}

void tick(mrpt::img::CImage& img, int x, int y, const std::string& text) {
  img.line(x, y, x + 6, y, mrpt::img::TColor(40, 40, 40));
  img.textOut(x + 10, y - 7, text, mrpt::img::TColor(30, 30, 30));
}

void drawLegend(mrpt::img::CImage& img, int x0, int top) {
  const char* labels[] = {"traversable", "non-trav.", "unknown"};
  for (int k = 0; k < 3; ++k) {
    const Rgb col = labelColor(core::Label(k));
    img.filledRectangle(x0, top + 30 * k, x0 + 18, top + 30 * k + 18, mrpt::img::TColor(col.r, col.g, col.b));
    img.textOut(x0 + 26, top + 30 * k + 2, labels[k], mrpt::img::TColor(30, 30, 30));
  }
}

}  // namespace

mrpt::opengl::CPointCloudColoured::Ptr cloudPoints(const ScoredCloud& c, const Frame& f, FigureColor mode,
                                                   float point_size) {
  auto pts = mrpt::opengl::CPointCloudColoured::Create();
  pts->setPointSize(point_size);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Rgb col = pointColor(c, f, i, mode);
    pts->push_back(f.p[i].x(), f.p[i].y(), f.p[i].z(), col.r / 255.f, col.g / 255.f, col.b / 255.f);
  }
  return pts;
}

mrpt::opengl::CSetOfLines::Ptr normalLines(const Frame& f) {
  auto lines = newSetOfLines();
  lines->setColor_u8(mrpt::img::TColor(30, 30, 30));
  lines->setLineWidth(1.5f);
  Frame cloud_box;
  for (const auto& p : f.p) cloud_box.extend(p);
  const float len = 0.04f * (cloud_box.hi - cloud_box.lo).norm();
  // One normal per cube of the segment's length (a dense scan near the sensor would bury its
  // neighbourhood in segments), then every k-th of those for at most ~1500.
  std::unordered_set<std::uint64_t> taken;
  std::vector<std::size_t> picked;
  for (std::size_t i = 0; i < f.p.size(); ++i) {
    if (!f.n[i].allFinite() || !(len > 0)) continue;
    const Eigen::Vector3f c = ((f.p[i] - cloud_box.lo) / len).array().floor();
    const std::uint64_t key = (std::uint64_t(c.x()) * 73856093u) ^ (std::uint64_t(c.y()) * 19349663u) ^
                              (std::uint64_t(c.z()) * 83492791u);
    if (taken.insert(key).second) picked.push_back(i);
  }
  const std::size_t step = std::max<std::size_t>(1, picked.size() / 1500);
  for (std::size_t k = 0; k < picked.size(); k += step) {
    const std::size_t i = picked[k];
    const Eigen::Vector3f e = f.p[i] + len * f.n[i];
    lines->appendLine(f.p[i].x(), f.p[i].y(), f.p[i].z(), e.x(), e.y(), e.z());
  }
  return lines;
}

mrpt::opengl::CCamera camera(const Frame& f, const RenderOptions& o, double aspect, double elevation_deg) {
  mrpt::opengl::CCamera cam;
  const double fov = 40.0;
  cam.setProjectiveFOVdeg(float(fov));
  const Eigen::Vector3f centre = 0.5f * (f.lo + f.hi);
  const Eigen::Vector3f at = o.look_at ? Eigen::Vector3f(f.rot * *o.look_at) : centre;
  cam.setPointingAt(at.x(), at.y(), at.z());
  if (o.view_from) {
    const Eigen::Vector3f d = f.rot * *o.view_from - at;
    if (!(d.norm() > 0)) throw std::invalid_argument("--view-from and --look-at are the same point");
    cam.setZoomDistance(d.norm());
    cam.setAzimuthDegrees(float(std::atan2(d.y(), d.x()) * 180.0 / M_PI));
    cam.setElevationDegrees(float(std::asin(d.z() / d.norm()) * 180.0 / M_PI));
    return cam;
  }
  const double radius = std::max(1e-3, 0.5 * double((f.hi - f.lo).norm()));
  const double half = std::min(fov, fov * aspect) * 0.5 * M_PI / 180.0;
  cam.setZoomDistance(float(1.0 * radius / std::sin(half)));
  cam.setAzimuthDegrees(defaultAzimuth(f, elevation_deg));
  cam.setElevationDegrees(float(elevation_deg));
  return cam;
}

void drawBar(mrpt::img::CImage& img, int x, int height, FigureColor mode, float z_lo, float z_hi) {
  const int x0 = x + 20, top = 60, bottom = height - 60, w = 26;
  img.selectTextFont("9x15");
  const char* names[] = {"zeta (UPD)", "label",      "cost",
                         "slope [deg]", "height [m]", "camera colour"};
  img.textOut(x0 - 6, top - 44, names[int(mode)], mrpt::img::TColor(20, 20, 20));
  if (mode == FigureColor::Rgb) return;  // the picture is its own legend
  if (mode == FigureColor::Label) return drawLegend(img, x0, top);
  const float lo_z = std::sqrt(2.0f) / 2.0f;
  double v0 = 1.0, v1 = lo_z;  // value at the top and the bottom of the bar
  if (mode == FigureColor::Cost) v0 = 1.0, v1 = 0.0;
  if (mode == FigureColor::Slope) v0 = kMaxSlopeDeg, v1 = 0.0;
  if (mode == FigureColor::Height) v0 = z_hi, v1 = z_lo;
  for (int y = top; y <= bottom; ++y) {
    const float v = float(v0 + (v1 - v0) * (y - top) / double(bottom - top));
    Rgb col;
    if (mode == FigureColor::Zeta) col = zetaColor(v);
    else if (mode == FigureColor::Cost) col = costColor(v);
    else col = ramp(float((v - std::min(v0, v1)) / std::max(1e-9, std::abs(v0 - v1))));
    img.line(x0, y, x0 + w, y, mrpt::img::TColor(col.r, col.g, col.b));
  }
  img.rectangle(x0, top, x0 + w, bottom, mrpt::img::TColor(40, 40, 40));
  const bool z = mode == FigureColor::Zeta;
  const int n = z ? 7 : 5;  // zeta: 1.00, 0.95, ..., 0.75 and sqrt(2)/2
  for (int k = 0; k < n; ++k) {
    const double v = z ? (k == 6 ? lo_z : 1.0 - 0.05 * k) : v0 + (v1 - v0) * k / (n - 1.0);
    const int y = top + int(std::lround((v - v0) / (v1 - v0) * (bottom - top)));
    const char* fmt = mode == FigureColor::Slope ? "%.0f" : (z ? "%.3f" : "%.2f");
    tick(img, x0 + w, y, mrpt::format(fmt, v));
  }
  if (z) {
    img.textOut(x0 - 6, top - 24, "regular", mrpt::img::TColor(40, 140, 60));
    img.textOut(x0 - 6, bottom + 12, "discontinuity", mrpt::img::TColor(30, 60, 200));
  }
}

}  // namespace upd::nav::detail
