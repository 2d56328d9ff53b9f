// A low smooth rock beside the robot's way, a dome 7 cm tall that the UPD at the loop's d_m reads
// flat (zeta above 0.95 all over), is non-traversable on the map the loop fuses with the shipped
// configs (the bump check on), out to the truth's extent (its foot grown by the truth's 5 cm
// border), on the side the camera sees; the ground round it stays open. Without the bump check
// the rock's cells read traversable.
#include "upd/nav/nav_config.h"
#include "upd/nav/navigation_loop.h"
#include "upd/sim/robot.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace upd::nav {
namespace {

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config";

// A base that stands where the test puts it.
class PlacedBase : public RobotBase {
 public:
  Pose2D pose;
  bool readState(BaseState& s) override {
    s.pose_world_robot = s.pose_odom_robot = pose;
    return true;
  }
  bool sendVelocity(const Twist2D&) override { return true; }
  bool stop(bool) override { return true; }
  double timeS() const override { return 0.0; }
};

TEST(NavBump, LowSmoothRockIsNonTraversableOutToTheTruthsExtent) {
  NavConfig config = loadNavConfig(kConfig + "/dune-kinect.ini", kConfig + "/dune-nav.ini");
  ASSERT_TRUE(config.step_edges.bumps) << "on in the shipped config";
  const Eigen::Vector2d lo(-1.0, -2.0), hi(6.0, 2.0);
  sim::Terrain t(lo, hi);
  sim::Rock rock;
  rock.center_xy = {2.3, 0.45};
  rock.radius_x_m = 0.3;
  rock.radius_y_m = 0.25;
  rock.height_m = 0.07;
  rock.yaw_rad = 0.4;
  t.add(rock);
  // The robot drives along y = 0 towards the rock's side, one frame every 0.1 m.
  PlacedBase base;
  NavigationLoop loop(base, config, core::ObstacleDetector::Upd);
  for (int k = 0; k < 8; ++k) {
    const double x = 0.1 * k;
    base.pose = Pose2D{x, 0.0, 0.0};
    const Eigen::Isometry3d body = sim::bodyPoseOnTerrain(t, {x, 0.0, 0.0}, config.body);
    const core::PointCloud cloud = sim::renderCameraWorld(t, body, config.camera,
                                                          config.depth_noise, 11 + k);
    loop.addFrame(cloud, 0.2 * k, body.translation().z());
  }
  const maps::TraversabilityGrid& grid = loop.grid();
  int checked = 0;
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    for (int cx = 0; cx < grid.sizeX(); ++cx) {
      const Eigen::Vector2d c = grid.cellCenter(cx, cy);
      if (t.truthAt(c.x(), c.y()) != core::Label::NonTraversable) continue;
      // The truth's rock and border (nothing else is non-traversable here), on the side the
      // camera sees: below the rock's centre line.
      if (c.y() > rock.center_xy.y() || !maps::isKnown(grid, c.x(), c.y())) continue;
      ++checked;
      EXPECT_EQ(maps::cellLabel(grid, c.x(), c.y()), core::Label::NonTraversable)
          << "cell " << c.transpose() << " of the rock read traversable";
    }
  }
  EXPECT_GE(checked, 6) << "the rock's near half is in view";
  // The ground 0.25 m beyond the rock's foot on the robot's side stays open.
  for (double x = 1.6; x <= 3.0; x += 0.1) {
    EXPECT_NE(maps::cellLabel(grid, x, 0.45 - 0.25 - 0.25 - 0.05),
              core::Label::NonTraversable)
        << "x " << x;
  }
}

}  // namespace
}  // namespace upd::nav
