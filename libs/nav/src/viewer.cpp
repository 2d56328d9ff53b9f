// The interactive viewer (viewer.h): the content is rebuilt into one CSetOfObjects on every
// change, the colour bar is an image viewport at the right, the help a set of text messages.
#include "upd/nav/viewer.h"
#include "figure_png.h"
#include "figure_scene.h"
#include "map_scene.h"
#include "window_grab.h"

#include <mrpt/core/format.h>
#include <mrpt/gui/CDisplayWindow3D.h>
#include <mrpt/opengl/CSetOfObjects.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <thread>
#include <vector>

namespace upd::nav {

bool displayAvailable() {
  for (const char* var : {"DISPLAY", "WAYLAND_DISPLAY"}) {
    const char* v = std::getenv(var);
    if (v != nullptr && *v != '\0') return true;
  }
  return false;
}

ScoredCloud scoredCloudOf(const core::ScoredFrame& frame) {
  ScoredCloud c;
  const auto& p = frame.cloud_world;
  const bool normals = frame.normals_world.size() == p.size(), zeta = frame.upd.zeta.size() == p.size();
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!p.isFinite(i)) continue;
    c.points.emplace_back(p.x[i], p.y[i], p.z[i]);
    c.normals.push_back(normals ? Eigen::Vector3f(frame.normals_world.nx[i], frame.normals_world.ny[i],
                                                  frame.normals_world.nz[i])
                                : Eigen::Vector3f::Constant(kNoValue));
    c.zeta.push_back(zeta ? frame.upd.zeta[i] : kNoValue);
    c.cost.push_back(i < frame.classes.cost.size() ? frame.classes.cost[i] : kNoValue);
    c.label.push_back(i < frame.classes.label.size() ? frame.classes.label[i] : core::Label::Unknown);
  }
  return c;
}

namespace {

std::atomic<bool> g_viewer_shown{false};

const char* const kColorNames[] = {"zeta", "label", "cost", "slope", "height", "rgb"};
const char* const kMapNames[] = {"grid", "octree", "none"};
const char* const kHelp[] = {
    "keys: z l c s h (1-5) colour by zeta, label, cost, slope, height",
    "      n normals   m map: grid / octree / none   r reset view",
    "      p screenshot   t help on/off   q Esc close",
    "mouse: left turn, wheel zoom, right or Shift+left pan"};

}  // namespace

struct Viewer::Impl {
  ViewerOptions o;
  mrpt::gui::CDisplayWindow3D::Ptr win;
  mrpt::opengl::CSetOfObjects::Ptr content = mrpt::opengl::CSetOfObjects::Create();
  mrpt::opengl::COpenGLViewport::Ptr bar;
  ScoredCloud cloud;
  MapSnapshot map;
  detail::Frame frame;
  bool help = true, camera_set = false;
  int shots = 0;

  void redraw();
  void drawTexts();
  void resetCamera();
};

void Viewer::Impl::redraw() {
  frame = detail::upright(cloud, o.up);
  Eigen::Vector3f lo, hi;
  if (map.bounds(lo, hi)) frame.extend(lo), frame.extend(hi);
  const float z_lo = frame.empty() ? 0.f : frame.lo.z(), z_hi = frame.empty() ? 1.f : frame.hi.z();
  mrpt::img::CImage bar_img(detail::kPanelWidth, o.height, mrpt::img::CH_RGB);
  bar_img.filledRectangle(0, 0, detail::kPanelWidth - 1, o.height - 1, mrpt::img::TColor(255, 255, 255));
  detail::drawBar(bar_img, 0, o.height, o.color, z_lo, z_hi);
  win->get3DSceneAndLock();
  content->clear();
  content->insert(detail::mapObjects(map, o.map, o.color, z_lo, z_hi));
  if (cloud.size() > 0) {
    content->insert(detail::cloudPoints(cloud, frame, o.color, 2.5f));
    if (o.normals) content->insert(detail::normalLines(frame));
  }
  bar->setImageView(std::move(bar_img));
  win->unlockAccess3DScene();
  if (!camera_set && !frame.empty()) resetCamera();
  if (o.follow_robot && !map.path.empty()) {
    const Eigen::Vector3f& at = map.path.back();
    win->setCameraPointingToPoint(at.x(), at.y(), at.z());
  }
  drawTexts();
  win->forceRepaint();
}

void Viewer::Impl::drawTexts() {
  mrpt::opengl::TFontParams font;
  font.color = mrpt::img::TColorf(0.1f, 0.1f, 0.1f);
  font.vfont_scale = 11;
  win->addTextMessage(8, -16, o.title, 0, font);
  std::string status = mrpt::format("colour: %s   normals: %s   %zu points", kColorNames[int(o.color)],
                                    o.normals ? "on" : "off", cloud.size());
  if (map.hasGrid() || !map.voxels.empty() || !map.path.empty()) {
    status += mrpt::format("   map: %s (%d x %d cells, %zu voxels)   path: %zu poses", kMapNames[int(o.map)], map.nx,
                           map.ny, map.voxels.size(), map.path.size());
  }
  win->addTextMessage(8, -32, status, 1, font);
  const std::size_t lines = sizeof(kHelp) / sizeof(kHelp[0]);
  for (std::size_t k = 0; k < lines; ++k) {  // at the bottom left
    win->addTextMessage(8, 8 + 15 * double(lines - 1 - k), help ? kHelp[k] : "", 2 + k, font);
  }
}

void Viewer::Impl::resetCamera() {
  if (frame.empty()) return;
  RenderOptions ro;
  detail::Frame f = frame;
  if (map.hasGrid() || !map.voxels.empty()) f.n.clear();  // a map: from behind (-x, -y)
  const mrpt::opengl::CCamera cam =
      detail::camera(f, ro, double(o.width - detail::kPanelWidth) / o.height, f.n.empty() ? 55.0 : 35.0);
  win->setFOV(cam.getProjectiveFOVdeg());
  win->setCameraPointingToPoint(cam.getPointingAtX(), cam.getPointingAtY(), cam.getPointingAtZ());
  win->setCameraZoom(o.follow_robot ? std::max(12.0f, cam.getZoomDistance()) : cam.getZoomDistance());
  win->setCameraAzimuthDeg(cam.getAzimuthDegrees());
  win->setCameraElevationDeg(cam.getElevationDegrees());
  camera_set = true;
}

Viewer::Viewer(const ViewerOptions& options) : impl_(std::make_unique<Impl>()) {
  if (!displayAvailable()) {
    throw std::runtime_error("the viewer needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set)");
  }
  auto& d = *impl_;
  d.o = options;
  g_viewer_shown = true;
  d.win = mrpt::gui::CDisplayWindow3D::Create(options.title, unsigned(options.width), unsigned(options.height));
  for (int k = 0; k < 100 && !d.win->isOpen(); ++k) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (!d.win->isOpen()) throw std::runtime_error("cannot open the viewer's window on display " +
                                                 std::string(std::getenv("DISPLAY") ? std::getenv("DISPLAY") : "?"));
  auto& scene = d.win->get3DSceneAndLock();
  scene->getViewport()->setCustomBackgroundColor(mrpt::img::TColorf(1, 1, 1));
  const double bar_w = double(detail::kPanelWidth) / options.width;
  scene->getViewport()->setViewportPosition(0, 0, 1.0 - bar_w, 1.0);
  scene->insert(d.content);
  d.bar = scene->createViewport("colour_bar");
  d.bar->setViewportPosition(1.0 - bar_w, 0, bar_w, 1.0);
  d.win->unlockAccess3DScene();
  d.redraw();
}

Viewer::~Viewer() = default;

void exitIfViewerShown(int code) {
  if (!g_viewer_shown) return;
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(code);
}

MapStyle Viewer::mapStyle() const { return impl_->o.map; }

bool Viewer::isOpen() const { return impl_->win && impl_->win->isOpen(); }

void Viewer::setContent(ScoredCloud cloud, MapSnapshot map) {
  impl_->cloud = std::move(cloud);
  impl_->map = std::move(map);
  if (isOpen()) impl_->redraw();
}

void Viewer::setMap(MapSnapshot map) {
  impl_->map = std::move(map);
  if (isOpen()) impl_->redraw();
}

void Viewer::pressKey(int key) {
  auto& d = *impl_;
  if (!isOpen()) return;
  const int k = std::tolower(key);
  const char* colours = "zlcsh";
  for (int i = 0; i < 5; ++i) {
    if (k == colours[i] || k == '1' + i) d.o.color = FigureColor(i);
  }
  if (k == 'n') d.o.normals = !d.o.normals;
  if (k == 'm') d.o.map = MapStyle((int(d.o.map) + 1) % 3);
  if (k == 't') d.help = !d.help;
  if (k == 'r') d.resetCamera();
  if (k == 'q' || k == 27) {
    d.win.reset();  // closes the window
    d.win = nullptr;
    return;
  }
  if (k == 'p') {
    const std::string png = mrpt::format("%s-%03d.png", d.o.screenshot_prefix.c_str(), ++d.shots);
    saveScreenshot(png);
    std::printf("screenshot: %s\n", png.c_str());
    return;
  }
  d.redraw();
}

bool Viewer::processEvents() {
  auto& d = *impl_;
  while (isOpen() && d.win->keyHit()) pressKey(d.win->getPushedKey());
  return isOpen();
}

void Viewer::saveScreenshot(const std::string& png) {
  auto& d = *impl_;
  if (!isOpen()) throw std::runtime_error(png + ": the window is closed");
  // What the X server shows once two reads 300 ms apart agree and it is not black (the window
  // has drawn the current content on its white background), at most ~10 s.
  mrpt::img::CImage last;
  bool have = false;
  for (int k = 0; k < 30; ++k) {
    d.win->forceRepaint();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    mrpt::img::CImage now = detail::grabWindow(d.o.title);
    const bool same = have && last.getWidth() == now.getWidth() && last.getHeight() == now.getHeight() &&
                      now.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY).total() > 0 &&
                      cv::norm(now.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY),
                               last.asCvMat<cv::Mat>(mrpt::img::SHALLOW_COPY), cv::NORM_INF) == 0;
    last = std::move(now);
    have = true;
    if (same) break;
  }
  writePngAtomically(last, png);
}

void Viewer::runUntilClosed() {
  while (processEvents()) std::this_thread::sleep_for(std::chrono::milliseconds(30));
}

}  // namespace upd::nav
