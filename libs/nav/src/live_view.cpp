#include "upd/nav/live_view.h"

#include "upd/maps/grid_export.h"
#include "upd/nav/obstacles.h"

#include <mrpt/gui/CDisplayWindow3D.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

namespace upd::nav {

bool displayAvailable() {
  for (const char* var : {"DISPLAY", "WAYLAND_DISPLAY"}) {
    const char* v = std::getenv(var);
    if (v != nullptr && *v != '\0') return true;
  }
  return false;
}

struct LiveView::Impl {
  mrpt::gui::CDisplayWindow3D::Ptr window;
  mrpt::opengl::CPointCloudColoured::Ptr cloud, map;
  mrpt::opengl::CSetOfLines::Ptr robot, route;
  sim::RobotBodyParams body;
};

LiveView::LiveView(const std::string& title, const sim::RobotBodyParams& body)
    : impl_(std::make_unique<Impl>()) {
  if (!displayAvailable()) {
    throw std::runtime_error("--view needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set)");
  }
  auto& d = *impl_;
  d.body = body;
  d.window = mrpt::gui::CDisplayWindow3D::Create(title, 1024, 768);
  d.cloud = mrpt::opengl::CPointCloudColoured::Create();
  d.cloud->setPointSize(2.0f);
  d.map = mrpt::opengl::CPointCloudColoured::Create();
  d.map->setPointSize(4.0f);
  d.robot = mrpt::opengl::CSetOfLines::Create();
  d.robot->setLineWidth(3.0f);
  d.robot->setColor(0.1f, 0.3f, 1.0f);
  d.route = mrpt::opengl::CSetOfLines::Create();
  d.route->setLineWidth(2.0f);
  d.route->setColor(0.0f, 0.0f, 0.0f);
  {
    auto& scene = d.window->get3DSceneAndLock();
    scene->insert(mrpt::opengl::CGridPlaneXY::Create(-20, 20, -20, 20, 0, 1));
    scene->insert(d.map);
    scene->insert(d.cloud);
    scene->insert(d.route);
    scene->insert(d.robot);
    d.window->unlockAccess3DScene();
  }
  d.window->setCameraZoom(12.0f);
  d.window->setCameraElevationDeg(50.0f);
}

LiveView::~LiveView() = default;

bool LiveView::isOpen() const { return impl_->window->isOpen(); }

void LiveView::update(const FrameEvidence& frame, const maps::TraversabilityGrid& grid,
                      const Pose2D& pose, const Route* route) {
  auto& d = *impl_;
  d.window->get3DSceneAndLock();
  // The cloud by zeta: red at zeta <= 0.7 (a 90 deg corner), green at 1; grey when not scored.
  d.cloud->clear();
  for (std::size_t i = 0; i < frame.cloud_world.size(); ++i) {
    if (!frame.cloud_world.isFinite(i)) continue;
    const float zeta = i < frame.upd.zeta.size() ? frame.upd.zeta[i] : std::nanf("");
    float r = 0.5f, g = 0.5f, b = 0.5f;
    if (std::isfinite(zeta)) {
      const float t = std::clamp((zeta - 0.7f) / 0.3f, 0.f, 1.f);
      r = 1.f - t;
      g = t;
      b = 0.f;
    } else if (i < frame.classes.label.size() && frame.classes.label[i] != core::Label::Unknown) {
      // Roughness index: no zeta, colour by label.
      const bool nt = frame.classes.label[i] == core::Label::NonTraversable;
      r = nt ? 1.f : 0.f;
      g = nt ? 0.f : 1.f;
    }
    d.cloud->push_back(frame.cloud_world.x[i], frame.cloud_world.y[i], frame.cloud_world.z[i], r, g,
                       b);
  }
  d.map->clear();
  maps::forEachKnownCell(grid, [&](int cx, int cy, const maps::GridCell& c) {
    const Eigen::Vector2d p = grid.cellCenter(cx, cy);
    const auto rgb = maps::traversabilityColourRgb(maps::probabilityOf(c, grid.params()));
    const float z = std::isfinite(c.elevation_m) ? c.elevation_m : 0.f;
    d.map->push_back(static_cast<float>(p.x()), static_cast<float>(p.y()), z - 0.01f,
                     rgb[0] / 255.f, rgb[1] / 255.f, rgb[2] / 255.f);
  });
  d.robot->clear();
  const double hl = 0.5 * d.body.length_m, hw = 0.5 * d.body.width_m;
  const Eigen::Vector2d corners[4] = {robotToWorld(pose, {hl, hw}), robotToWorld(pose, {hl, -hw}),
                                      robotToWorld(pose, {-hl, -hw}),
                                      robotToWorld(pose, {-hl, hw})};
  for (int k = 0; k < 4; ++k) {
    const auto& a = corners[k];
    const auto& b = corners[(k + 1) % 4];
    d.robot->appendLine(a.x(), a.y(), 0.05, b.x(), b.y(), 0.05);
  }
  const Eigen::Vector2d nose = robotToWorld(pose, {hl + 0.2, 0.0});
  d.robot->appendLine(pose.x_m, pose.y_m, 0.05, nose.x(), nose.y(), 0.05);
  d.route->clear();
  if (route != nullptr && route->found) {
    for (std::size_t i = 1; i < route->path_world.size(); ++i) {
      const auto& a = route->path_world[i - 1];
      const auto& b = route->path_world[i];
      d.route->appendLine(a.x(), a.y(), 0.03, b.x(), b.y(), 0.03);
    }
  }
  d.window->unlockAccess3DScene();
  d.window->setCameraPointingToPoint(static_cast<float>(pose.x_m), static_cast<float>(pose.y_m),
                                     0.f);
  d.window->forceRepaint();
}

}  // namespace upd::nav
