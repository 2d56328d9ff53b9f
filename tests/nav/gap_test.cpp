// A passage of the robot's width plus 0.5 m between two walls stays open on the map the loop
// fuses from the UPD with the shipped configs: the band the UPD marks round the walls leaves a
// route through the gap.
#include "upd/nav/nav_config.h"
#include "upd/nav/navigation_loop.h"
#include "upd/nav/route_planner.h"
#include "upd/sim/robot.h"

#include <gtest/gtest.h>

#include <string>

namespace upd::nav {
namespace {

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config";

TEST(NavGap, RobotWidthPlusHalfAMetreStaysOpen) {
  const NavConfig config = loadNavConfig(kConfig + "/dune-kinect.ini", kConfig + "/dune-nav.ini");
  const double gap = config.body.width_m + 0.5;
  // Walls across the world (3 m wide, fenced, all in view) at x = 3.5 m (0.15 m thick, 0.6 m
  // high) with the gap round y = 0; the robot 3 m before them.
  const Eigen::Vector2d lo(-1.0, -1.5), hi(8.0, 1.5);
  sim::Terrain t(lo, hi);
  for (const double side : {-1.0, 1.0}) {
    sim::Box w;
    w.length_m = 0.15;
    w.width_m = 2.0 - 0.5 * gap;
    w.center_xy = {3.5, side * (0.5 * gap + 0.5 * w.width_m)};
    w.height_m = 0.6;
    w.wall = true;
    t.add(w);
  }
  SimulatedDiffDrive base(Pose2D{0.5, 0.0, 0.0}, config.base);
  NavigationLoop loop(base, config, core::ObstacleDetector::Upd);
  const Eigen::Isometry3d body = sim::bodyPoseOnTerrain(t, {0.5, 0.0, 0.0}, config.body);
  for (int k = 0; k < 5; ++k) {
    const core::PointCloud cloud = sim::renderCameraWorld(t, body, config.camera,
                                                          config.depth_noise, 7 + k);
    loop.addFrame(cloud, 0.2 * k, body.translation().z());
  }
  // The walls' faces are on the map, the gap between them is not closed.
  EXPECT_EQ(maps::cellLabel(loop.grid(), 3.42, 0.5 * gap + 0.3), core::Label::NonTraversable);
  EXPECT_EQ(maps::cellLabel(loop.grid(), 3.42, -0.5 * gap - 0.3), core::Label::NonTraversable);
  const Route r = planRoute(loop.grid(), rectangleFence(lo, hi, 0.05), {0.5, 0.0}, {6.0, 0.0},
                            config.route);
  ASSERT_TRUE(r.found);
  for (std::size_t i = 1; i < r.path_world.size(); ++i) {
    const Eigen::Vector2d a = r.path_world[i - 1], b = r.path_world[i];
    if ((a.x() - 3.5) * (b.x() - 3.5) <= 0.0) {
      EXPECT_LT(std::abs(a.y()), 0.5 * gap) << "the route crosses the wall line in the gap";
    }
  }
  EXPECT_LT(r.length_m, 6.0) << "straight through, no detour";
}

}  // namespace
}  // namespace upd::nav
