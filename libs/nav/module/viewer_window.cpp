// The viewer module (viewer_window.h): the window of the interactive viewer (viewer.h), an MRPT
// CDisplayWindow3D. The content is rebuilt into one CSetOfObjects on every change, the colour
// bar is an image viewport at the right, the help a set of text messages.
#include "../src/figure_png.h"
#include "../src/figure_scene.h"
#include "../src/map_scene.h"
#include "../src/viewer_window.h"
#include "window_grab.h"

#include <mrpt/core/format.h>
#include <mrpt/gui/CDisplayWindow3D.h>
#include <mrpt/opengl/CSetOfObjects.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <thread>

namespace upd::nav::detail {

namespace {

const char* const kColorNames[] = {"zeta", "label", "cost", "slope", "height", "rgb"};
const char* const kMapNames[] = {"grid", "octree", "none"};
const char* const kHelp[] = {
    "keys: z l c s h (1-5) colour by zeta, label, cost, slope, height",
    "      n normals   m map: grid / octree / none   r reset view",
    "      p screenshot   t help on/off   q Esc close",
    "mouse: left turn, wheel zoom, right or Shift+left pan"};

class Window final : public ViewerWindow {
 public:
  explicit Window(const ViewerOptions& options);
  MapStyle mapStyle() const override { return o.map; }
  bool isOpen() const override { return win && win->isOpen(); }
  void setContent(ScoredCloud c, MapSnapshot m) override {
    cloud = std::move(c);
    map = std::move(m);
    if (isOpen()) redraw();
  }
  void setMap(MapSnapshot m) override {
    map = std::move(m);
    if (isOpen()) redraw();
  }
  void pressKey(int key) override;
  bool processEvents() override {
    while (isOpen() && win->keyHit()) pressKey(win->getPushedKey());
    return isOpen();
  }
  void saveScreenshot(const std::string& png) override;

 private:
  void redraw();
  void drawTexts();
  void resetCamera();

  ViewerOptions o;
  mrpt::gui::CDisplayWindow3D::Ptr win;
  mrpt::opengl::CSetOfObjects::Ptr content = mrpt::opengl::CSetOfObjects::Create();
  mrpt::opengl::COpenGLViewport::Ptr bar;
  ScoredCloud cloud;
  MapSnapshot map;
  Frame frame;
  bool help = true, camera_set = false;
  int shots = 0;
};

Window::Window(const ViewerOptions& options) : o(options) {
  win = mrpt::gui::CDisplayWindow3D::Create(options.title, unsigned(options.width), unsigned(options.height));
  for (int k = 0; k < 100 && !win->isOpen(); ++k) std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (!win->isOpen()) throw std::runtime_error("cannot open the viewer's window on display " +
                                               std::string(std::getenv("DISPLAY") ? std::getenv("DISPLAY") : "?"));
  auto& scene = win->get3DSceneAndLock();
  scene->getViewport()->setCustomBackgroundColor(mrpt::img::TColorf(1, 1, 1));
  const double bar_w = double(kPanelWidth) / options.width;
  scene->getViewport()->setViewportPosition(0, 0, 1.0 - bar_w, 1.0);
  scene->insert(content);
  bar = scene->createViewport("colour_bar");
  bar->setViewportPosition(1.0 - bar_w, 0, bar_w, 1.0);
  win->unlockAccess3DScene();
  redraw();
}

void Window::redraw() {
  frame = upright(cloud, o.up);
  Eigen::Vector3f lo, hi;
  if (map.bounds(lo, hi)) frame.extend(lo), frame.extend(hi);
  const float z_lo = frame.empty() ? 0.f : frame.lo.z(), z_hi = frame.empty() ? 1.f : frame.hi.z();
  mrpt::img::CImage bar_img(kPanelWidth, o.height, mrpt::img::CH_RGB);
  bar_img.filledRectangle(0, 0, kPanelWidth - 1, o.height - 1, mrpt::img::TColor(255, 255, 255));
  drawBar(bar_img, 0, o.height, o.color, z_lo, z_hi);
  win->get3DSceneAndLock();
  content->clear();
  content->insert(mapObjects(map, o.map, o.color, z_lo, z_hi));
  if (cloud.size() > 0) {
    content->insert(cloudPoints(cloud, frame, o.color, 2.5f));
    if (o.normals) content->insert(normalLines(frame));
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

void Window::drawTexts() {
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

void Window::resetCamera() {
  if (frame.empty()) return;
  RenderOptions ro;
  Frame f = frame;
  if (map.hasGrid() || !map.voxels.empty()) f.n.clear();  // a map: from behind (-x, -y)
  const mrpt::opengl::CCamera cam =
      camera(f, ro, double(o.width - kPanelWidth) / o.height, f.n.empty() ? 55.0 : 35.0);
  win->setFOV(cam.getProjectiveFOVdeg());
  win->setCameraPointingToPoint(cam.getPointingAtX(), cam.getPointingAtY(), cam.getPointingAtZ());
  win->setCameraZoom(o.follow_robot ? std::max(12.0f, cam.getZoomDistance()) : cam.getZoomDistance());
  win->setCameraAzimuthDeg(cam.getAzimuthDegrees());
  win->setCameraElevationDeg(cam.getElevationDegrees());
  camera_set = true;
}

void Window::pressKey(int key) {
  if (!isOpen()) return;
  const int k = std::tolower(key);
  const char* colours = "zlcsh";
  for (int i = 0; i < 5; ++i) {
    if (k == colours[i] || k == '1' + i) o.color = FigureColor(i);
  }
  if (k == 'n') o.normals = !o.normals;
  if (k == 'm') o.map = MapStyle((int(o.map) + 1) % 3);
  if (k == 't') help = !help;
  if (k == 'r') resetCamera();
  if (k == 'q' || k == 27) {
    win.reset();  // closes the window
    win = nullptr;
    return;
  }
  if (k == 'p') {
    const std::string png = mrpt::format("%s-%03d.png", o.screenshot_prefix.c_str(), ++shots);
    saveScreenshot(png);
    std::printf("screenshot: %s\n", png.c_str());
    return;
  }
  redraw();
}

void Window::saveScreenshot(const std::string& png) {
  if (!isOpen()) throw std::runtime_error(png + ": the window is closed");
  // What the X server shows once two reads 300 ms apart agree and it is not black (the window
  // has drawn the current content on its white background), at most ~10 s.
  mrpt::img::CImage last;
  bool have = false;
  for (int k = 0; k < 30; ++k) {
    win->forceRepaint();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    mrpt::img::CImage now = grabWindow(o.title);
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

std::unique_ptr<ViewerWindow> open(const ViewerOptions& options) {
  return std::make_unique<Window>(options);
}

}  // namespace

}  // namespace upd::nav::detail

extern "C" const upd::nav::detail::ViewerModule upd_nav_viewer_module = {&upd::nav::detail::open};
