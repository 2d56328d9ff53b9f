// The view of `upd live --view` (live_view.h).
#include "live_view.h"

namespace upd::app {

namespace {

nav::ViewerOptions liveViewOptions(const std::string& title) {
  nav::ViewerOptions o;
  o.title = title;
  o.follow_robot = true;
  return o;
}

}  // namespace

LiveView::LiveView(const std::string& title, const sim::RobotBodyParams& body)
    : viewer_(liveViewOptions(title)), body_(body) {}

void LiveView::show(const core::ScoredFrame& frame, const maps::TraversabilityGrid& grid,
                    const nav::Pose2D& pose, const nav::Route* route) {
  if (!viewer_.processEvents()) return;
  const Eigen::Vector3f here(float(pose.x_m), float(pose.y_m), 0.f);
  if (path_.empty() || (path_.back() - here).norm() > 0.02f) path_.push_back(here);
  nav::MapSnapshot map;
  nav::snapshotGrid(grid, map);
  map.path = path_;
  map.robot_length_m = float(body_.length_m);
  map.robot_width_m = float(body_.width_m);
  map.robot_yaw_rad = float(pose.yaw_rad);
  if (route != nullptr && route->found) {
    for (const auto& p : route->path_world) map.route.emplace_back(float(p.x()), float(p.y()), 0.f);
  }
  viewer_.setContent(nav::scoredCloudOf(frame), std::move(map));
}

}  // namespace upd::app
