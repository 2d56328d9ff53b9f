// The 3D figure: a scored cloud as coloured points (and normals as short segments) rendered
// off-screen by CFBORender, then a colour bar or legend drawn beside it with CImage primitives.
#include "upd/nav/figure.h"
#include "figure_png.h"

#include <mrpt/img/CImage.h>
#include <mrpt/opengl/CFBORender.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace upd::nav {
namespace {

constexpr int kPanelWidth = 170;  // the colour bar's column at the right

Rgb ramp(float t) {  // blue - cyan - yellow - red
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

constexpr float kMaxSlopeDeg = 45.0f;

struct Frame {  // the cloud rotated so that up is +z, and its extent
  std::vector<Eigen::Vector3f> p, n;
  Eigen::Matrix3f rot;
  Eigen::Vector3f lo, hi;
};

Frame upright(const ScoredCloud& c, const Eigen::Vector3f& up) {
  if (!(up.norm() > 0)) throw std::invalid_argument("the up vector must not be zero");
  Frame f;
  f.rot = Eigen::Quaternionf::FromTwoVectors(up.normalized(), Eigen::Vector3f::UnitZ()).toRotationMatrix();
  f.lo = Eigen::Vector3f::Constant(1e30f);
  f.hi = -f.lo;
  for (std::size_t i = 0; i < c.size(); ++i) {
    f.p.push_back(f.rot * c.points[i]);
    f.n.push_back(f.rot * c.normals[i]);
    f.lo = f.lo.cwiseMin(f.p.back());
    f.hi = f.hi.cwiseMax(f.p.back());
  }
  return f;
}

Rgb pointColor(const ScoredCloud& c, const Frame& f, std::size_t i, FigureColor mode) {
  switch (mode) {
    case FigureColor::Zeta: return zetaColor(c.zeta[i]);
    case FigureColor::Label: return labelColor(c.label[i]);
    case FigureColor::Cost: return costColor(c.cost[i]);
    case FigureColor::Slope: {
      if (!f.n[i].allFinite()) return {150, 150, 150};
      const float deg = std::acos(std::min(1.0f, std::abs(f.n[i].z()))) * 180.0f / float(M_PI);
      return ramp(deg / kMaxSlopeDeg);
    }
    case FigureColor::Height: {
      const float span = f.hi.z() - f.lo.z();
      return ramp(span > 0 ? (f.p[i].z() - f.lo.z()) / span : 0.0f);
    }
    case FigureColor::Rgb:
      if (c.rgb.size() != c.size()) return {150, 150, 150};
      return {c.rgb[i][0], c.rgb[i][1], c.rgb[i][2]};
  }
  return {};
}

void addCloud(mrpt::opengl::COpenGLScene& scene, const ScoredCloud& c, const Frame& f,
              const RenderOptions& o) {
  auto pts = mrpt::opengl::CPointCloudColoured::Create();
  pts->setPointSize(o.point_size);
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Rgb col = pointColor(c, f, i, o.color);
    pts->push_back(f.p[i].x(), f.p[i].y(), f.p[i].z(), col.r / 255.f, col.g / 255.f, col.b / 255.f);
  }
  scene.insert(pts);
  if (!o.normals) return;
  auto lines = mrpt::opengl::CSetOfLines::Create();
  lines->setColor_u8(mrpt::img::TColor(30, 30, 30));
  lines->setLineWidth(1.5f);
  const float len = 0.04f * (f.hi - f.lo).norm();
  const std::size_t step = std::max<std::size_t>(1, c.size() / 1500);
  for (std::size_t i = 0; i < c.size(); i += step) {
    if (!f.n[i].allFinite()) continue;
    const Eigen::Vector3f e = f.p[i] + len * f.n[i];
    lines->appendLine(f.p[i].x(), f.p[i].y(), f.p[i].z(), e.x(), e.y(), e.z());
  }
  scene.insert(lines);
}

constexpr double kElevationDeg = 35.0;

// Behind (-x) and to the side, unless the surfaces face another way: of the four diagonal
// views, the first that sees the most of the normals' front sides (the pipeline orients normals
// towards the sensor), so a wall is not seen from its back.
float defaultAzimuth(const Frame& f) {
  const float candidates[] = {-140.0f, 140.0f, -40.0f, 40.0f};
  float best = candidates[0];
  double best_score = -1e300;
  for (float az : candidates) {
    const double a = az * M_PI / 180.0, e = kElevationDeg * M_PI / 180.0;
    const Eigen::Vector3f d(float(std::cos(e) * std::cos(a)), float(std::cos(e) * std::sin(a)), float(std::sin(e)));
    double score = 0;
    for (const auto& n : f.n) if (n.allFinite()) score += n.dot(d);
    if (score > best_score + 1e-6 * f.n.size()) best = az, best_score = score;
  }
  return best;
}

mrpt::opengl::CCamera camera(const Frame& f, const RenderOptions& o, double aspect) {
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
  cam.setAzimuthDegrees(defaultAzimuth(f));
  cam.setElevationDegrees(float(kElevationDeg));
  return cam;
}

void tick(mrpt::img::CImage& img, int x, int y, const std::string& text) {
  img.line(x, y, x + 6, y, mrpt::img::TColor(40, 40, 40));
  img.textOut(x + 10, y - 7, text, mrpt::img::TColor(30, 30, 30));
}

void drawBar(mrpt::img::CImage& img, const Frame& f, const RenderOptions& o) {
  const int x0 = o.width - kPanelWidth + 20, top = 60, bottom = o.height - 60, w = 26;
  img.selectTextFont("9x15");
  const char* names[] = {"zeta (UPD)", "label", "cost", "slope [deg]", "height [m]", "camera colour"};
  img.textOut(x0 - 6, top - 44, names[int(o.color)], mrpt::img::TColor(20, 20, 20));
  if (o.color == FigureColor::Rgb) return;  // the picture is its own legend
  if (o.color == FigureColor::Label) {
    const char* labels[] = {"traversable", "non-trav.", "unknown"};
    for (int k = 0; k < 3; ++k) {
      const Rgb col = labelColor(core::Label(k));
      img.filledRectangle(x0, top + 30 * k, x0 + 18, top + 30 * k + 18, mrpt::img::TColor(col.r, col.g, col.b));
      img.textOut(x0 + 26, top + 30 * k + 2, labels[k], mrpt::img::TColor(30, 30, 30));
    }
    return;
  }
  const float lo_z = std::sqrt(2.0f) / 2.0f;
  double v0 = 1.0, v1 = lo_z;  // value at the top and the bottom of the bar
  if (o.color == FigureColor::Cost) v0 = 1.0, v1 = 0.0;
  if (o.color == FigureColor::Slope) v0 = kMaxSlopeDeg, v1 = 0.0;
  if (o.color == FigureColor::Height) v0 = f.hi.z(), v1 = f.lo.z();
  for (int y = top; y <= bottom; ++y) {
    const float v = float(v0 + (v1 - v0) * (y - top) / double(bottom - top));
    Rgb col;
    if (o.color == FigureColor::Zeta) col = zetaColor(v);
    else if (o.color == FigureColor::Cost) col = costColor(v);
    else col = ramp(float((v - std::min(v0, v1)) / std::max(1e-9, std::abs(v0 - v1))));
    img.line(x0, y, x0 + w, y, mrpt::img::TColor(col.r, col.g, col.b));
  }
  img.rectangle(x0, top, x0 + w, bottom, mrpt::img::TColor(40, 40, 40));
  const bool z = o.color == FigureColor::Zeta;
  const int n = z ? 7 : 5;  // zeta: 1.00, 0.95, ..., 0.75 and sqrt(2)/2
  for (int k = 0; k < n; ++k) {
    const double v = z ? (k == 6 ? lo_z : 1.0 - 0.05 * k) : v0 + (v1 - v0) * k / (n - 1.0);
    const int y = top + int(std::lround((v - v0) / (v1 - v0) * (bottom - top)));
    const char* fmt = o.color == FigureColor::Slope ? "%.0f" : (o.color == FigureColor::Zeta ? "%.3f" : "%.2f");
    tick(img, x0 + w, y, mrpt::format(fmt, v));
  }
  if (o.color == FigureColor::Zeta) {
    img.textOut(x0 - 6, top - 24, "regular", mrpt::img::TColor(40, 140, 60));
    img.textOut(x0 - 6, bottom + 12, "discontinuity", mrpt::img::TColor(30, 60, 200));
  }
}

}  // namespace

void renderFigure(const ScoredCloud& cloud, const RenderOptions& o, const std::string& png) {
  if (o.width < 320 || o.height < 240 || o.width > 8192 || o.height > 8192)
    throw std::invalid_argument("figure size " + std::to_string(o.width) + "x" + std::to_string(o.height) +
                                " out of range (320x240 to 8192x8192)");
  if (cloud.size() == 0) throw std::invalid_argument("nothing to render: the cloud is empty");
  const Frame f = upright(cloud, o.up);
  mrpt::opengl::COpenGLScene scene;
  scene.getViewport()->setCustomBackgroundColor(mrpt::img::TColorf(1, 1, 1));
  addCloud(scene, cloud, f, o);

  // CFBORender reads the pixels back with OpenGL's default 4-byte row alignment: an RGB row
  // of a width that is not a multiple of 4 overruns the image (heap corruption in MRPT 2.5).
  const int w3d = (o.width - kPanelWidth) / 4 * 4;
  const mrpt::opengl::CCamera cam = camera(f, o, double(w3d) / o.height);
  mrpt::img::CImage view;
  try {
    mrpt::opengl::CFBORender fbo(unsigned(w3d), unsigned(o.height));
    fbo.getCamera(scene) = cam;
    fbo.render_RGB(scene, view);
  } catch (const std::exception& e) {  // MRPT's messages span lines (with a call trace)
    std::string first = e.what();
    first = first.substr(0, first.find('\n'));
    throw std::runtime_error("off-screen rendering (CFBORender, EGL) failed: " + first);
  }

  mrpt::img::CImage out(o.width, o.height, mrpt::img::CH_RGB);
  out.filledRectangle(0, 0, o.width - 1, o.height - 1, mrpt::img::TColor(255, 255, 255));
  out.drawImage(0, 0, view);
  out.line(w3d, 20, w3d, o.height - 20, mrpt::img::TColor(210, 210, 210));
  drawBar(out, f, o);
  if (!o.title.empty()) {
    out.selectTextFont("10x20");
    out.textOut(16, 12, o.title, mrpt::img::TColor(20, 20, 20));
  }
  writePngAtomically(out, png);
}

}  // namespace upd::nav
