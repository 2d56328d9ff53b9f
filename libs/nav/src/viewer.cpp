// The interactive viewer (viewer.h): each Viewer drives a window of the viewer module
// (viewer_window.h), loaded when the first viewer opens.
#include "upd/nav/viewer.h"
#include "upd/mrpt_bridge/module.h"
#include "viewer_window.h"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <stdexcept>
#include <thread>

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

const detail::ViewerModule& viewerModule() {
#ifdef UPD_VIEWER_MODULE
  static const char here = 0;
  return mrpt_bridge::moduleEntry<detail::ViewerModule>(UPD_VIEWER_MODULE,
                                                        "upd_nav_viewer_module", &here);
#else
  return upd_nav_viewer_module;
#endif
}

}  // namespace

detail::ViewerWindow::~ViewerWindow() = default;

struct Viewer::Impl {
  std::unique_ptr<detail::ViewerWindow> window;
};

Viewer::Viewer(const ViewerOptions& options) : impl_(std::make_unique<Impl>()) {
  if (!displayAvailable()) {
    throw std::runtime_error("the viewer needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set)");
  }
  const detail::ViewerModule& module = viewerModule();
  g_viewer_shown = true;
  impl_->window = module.open(options);
}

Viewer::~Viewer() = default;

void exitIfViewerShown(int code) {
  if (!g_viewer_shown) return;
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(code);
}

MapStyle Viewer::mapStyle() const { return impl_->window->mapStyle(); }

bool Viewer::isOpen() const { return impl_->window->isOpen(); }

void Viewer::setContent(ScoredCloud cloud, MapSnapshot map) {
  impl_->window->setContent(std::move(cloud), std::move(map));
}

void Viewer::setMap(MapSnapshot map) { impl_->window->setMap(std::move(map)); }

void Viewer::pressKey(int key) { impl_->window->pressKey(key); }

bool Viewer::processEvents() { return impl_->window->processEvents(); }

void Viewer::saveScreenshot(const std::string& png) { impl_->window->saveScreenshot(png); }

void Viewer::runUntilClosed() {
  while (processEvents()) std::this_thread::sleep_for(std::chrono::milliseconds(30));
}

}  // namespace upd::nav
