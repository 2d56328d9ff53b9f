// The navigator bridge: a known map and pose give known obstacle points in the robot frame.
#include "upd/maps/grid_fusion.h"
#include "upd/nav/nav_interface.h"
#include "upd/nav/obstacles.h"
#include "upd/nav/robot_base.h"

#include <gtest/gtest.h>
#include <mrpt/kinematics/CVehicleVelCmd_DiffDriven.h>
#include <mrpt/maps/CSimplePointsMap.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace core = upd::core;

namespace upd::nav {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A fixed 10 m window around the origin with the given world points fused as NonTraversable
// (five frames, so they are well above the threshold) and one Traversable point.
maps::TraversabilityGrid gridWith(const std::vector<Eigen::Vector2d>& nontrav_world) {
  maps::GridParams gp;
  gp.cell_size_m = 0.1;
  gp.extent_m = 10.0;
  gp.follow_robot = false;
  maps::TraversabilityGrid grid(gp);
  std::vector<float> x, y, z;
  std::vector<core::Label> label;
  for (const auto& p : nontrav_world) {
    x.push_back(static_cast<float>(p.x()));
    y.push_back(static_cast<float>(p.y()));
    z.push_back(0.2f);
    label.push_back(core::Label::NonTraversable);
  }
  x.push_back(-2.05f);
  y.push_back(-2.05f);
  z.push_back(0.f);
  label.push_back(core::Label::Traversable);
  maps::PointsWorld view;
  view.x = x.data();
  view.y = y.data();
  view.z = z.data();
  view.label = label.data();
  view.size = x.size();
  for (int k = 0; k < 5; ++k) maps::integrateScan(grid, view, {0, 0}, k, maps::FusionParams{});
  return grid;
}

TEST(NavFrames, WorldToRobotInvertsRobotToWorld) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0), a(-kPi, kPi);
  for (int i = 0; i < 200; ++i) {
    const Pose2D pose{u(rng), u(rng), a(rng)};
    const Eigen::Vector2d p(u(rng), u(rng));
    const Eigen::Vector2d back = robotToWorld(pose, worldToRobot(pose, p));
    EXPECT_NEAR(back.x(), p.x(), 1e-9);
    EXPECT_NEAR(back.y(), p.y(), 1e-9);
    // Distances are kept.
    EXPECT_NEAR(worldToRobot(pose, p).norm(), std::hypot(p.x() - pose.x_m, p.y() - pose.y_m), 1e-9);
  }
}

TEST(NavFrames, KnownPoses) {
  // Facing +y from (1, 1): a point 2 m further along +y is 2 m ahead; +x is to the right.
  const Pose2D pose{1.0, 1.0, kPi / 2};
  const Eigen::Vector2d ahead = worldToRobot(pose, {1.0, 3.0});
  EXPECT_NEAR(ahead.x(), 2.0, 1e-12);
  EXPECT_NEAR(ahead.y(), 0.0, 1e-12);
  const Eigen::Vector2d right = worldToRobot(pose, {2.0, 1.0});
  EXPECT_NEAR(right.x(), 0.0, 1e-12);
  EXPECT_NEAR(right.y(), -1.0, 1e-12);
}

TEST(NavObstacleSource, MapCellsComeOutInTheRobotFrame) {
  // One obstacle cell, centre (3.05, 1.05); the robot at (1, 1) facing +y.
  const auto grid = gridWith({{3.04, 1.06}});
  ObstacleSource src;
  src.setMap(&grid);
  const auto pts = src.pointsInRobot({1.0, 1.0, kPi / 2});
  ASSERT_EQ(pts.size(), 1u);
  // World offset (2.05, 0.05) seen from a robot facing +y: 0.05 ahead, 2.05 to the right.
  EXPECT_NEAR(pts[0].x(), 0.05, 1e-9);
  EXPECT_NEAR(pts[0].y(), -2.05, 1e-9);
}

// An obstacle may fill its map cell to the border: a polygon that keeps its margin from the
// obstacle points keeps it from every part of the cell, not only from its centre. Sampled over
// robot positions round a block of cells: the nearest obstacle point is never farther than the
// nearest point of the cells plus the points' spacing along the border (half a cell's diagonal
// would be the centre's excess).
TEST(NavObstacleSource, MapCellsReachTheirBorder) {
  const std::vector<Eigen::Vector2d> cells = {{1.05, 0.05}, {1.15, 0.05}, {1.15, 0.15}};
  const auto grid = gridWith(cells);
  ObstacleParams p;  // 5 cm decimation
  p.map_cell_border = true;
  p.map_cell_border_range_m = 10.0;  // every cell here
  ObstacleSource src(p);
  src.setMap(&grid);
  const double half = 0.05;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.5, 1.7);
  for (int k = 0; k < 300; ++k) {
    const Pose2D pose{u(rng), u(rng) - 1.0, 0.0};
    const Eigen::Vector2d robot(pose.x_m, pose.y_m);
    double to_cells = 1e9;
    for (const auto& c : cells) {
      const Eigen::Vector2d d = ((robot - c).cwiseAbs().array() - half).cwiseMax(0.0).matrix();
      to_cells = std::min(to_cells, d.norm());
    }
    if (to_cells < 0.02) continue;  // inside or at the cells
    double to_points = 1e9;
    for (const auto& q : src.pointsInRobot(pose)) to_points = std::min(to_points, q.norm());
    // Points every half cell along the border: the nearest is at most a quarter cell along the
    // border from the nearest point of the cells; the centre alone is half a cell farther.
    EXPECT_LE(to_points, std::hypot(to_cells, 0.5 * half) + 1e-6) << robot.transpose();
    EXPECT_GE(to_points, to_cells - 1e-6) << robot.transpose();
  }
  // The border lies on the cells: nothing beyond them.
  for (const auto& q : src.pointsInRobot({0.0, 0.0, 0.0})) {
    EXPECT_GE(q.x(), 1.0 - 1e-6);
    EXPECT_LE(q.x(), 1.2 + 1e-6);
    EXPECT_GE(q.y(), 0.0 - 1e-6);
    EXPECT_LE(q.y(), 0.2 + 1e-6);
  }
}

// Only cells near the robot give their border: a cell farther than map_cell_border_range_m
// gives its centre alone, a near one its centre and border (3 x 3 points on the half-cell
// lattice).
TEST(NavObstacleSource, CellBordersOnlyNearTheRobot) {
  const auto grid = gridWith({{1.05, 0.05}, {3.05, 0.05}});
  ObstacleParams p;
  p.map_cell_border = true;
  p.map_cell_border_range_m = 1.5;
  ObstacleSource src(p);
  src.setMap(&grid);
  int near = 0, far = 0;
  for (const auto& q : src.pointsInRobot({0.0, 0.0, 0.0})) (q.x() < 2.0 ? near : far) += 1;
  EXPECT_EQ(near, 9);
  EXPECT_EQ(far, 1);
  p.map_cell_border_range_m = 0.0;
  EXPECT_THROW(ObstacleSource{p}, std::invalid_argument);
}

TEST(NavObstacleSource, RangeAndSourcesAreHonoured) {
  const auto grid = gridWith({{1.05, 0.05}, {4.55, 0.05}});
  ObstacleParams p;
  p.range_m = 3.0;
  ObstacleSource src(p);
  src.setMap(&grid);
  src.setFrameObstacles({{0.0, 2.0}, {0.0, 3.5}});
  src.setFixedObstacles({{-2.0, 0.0}});
  auto pts = src.pointsInRobot({0.0, 0.0, 0.0});
  // In range: the map cell at 1.05, the frame point at 2 and the fixed one at 2 m; out of range:
  // the cell at 4.55 and the frame point at 3.5.
  ASSERT_EQ(pts.size(), 3u);
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) { return a.x() < b.x(); });
  EXPECT_NEAR(pts[0].x(), -2.0, 1e-9);
  EXPECT_NEAR(pts[1].y(), 2.0, 1e-9);
  EXPECT_NEAR(pts[2].x(), 1.05, 1e-9);

  p.use_map = false;
  p.use_current_frame = false;
  ObstacleSource fixed_only(p);
  fixed_only.setMap(&grid);
  fixed_only.setFrameObstacles({{0.0, 2.0}});
  fixed_only.setFixedObstacles({{-2.0, 0.0}});
  EXPECT_EQ(fixed_only.pointsInRobot({0.0, 0.0, 0.0}).size(), 1u);
}

TEST(NavObstacleSource, PointsAreThinnedToOnePerSquare) {
  ObstacleParams p;
  p.decimation_m = 0.1;
  ObstacleSource src(p);
  std::vector<Eigen::Vector2d> dense;
  for (int i = 0; i < 100; ++i) dense.emplace_back(1.0 + 0.001 * i, 0.01);  // inside 0.1 m
  src.setFrameObstacles(dense);
  EXPECT_EQ(src.pointsInRobot({0.0, 0.0, 0.3}).size(), 1u);
}

TEST(NavObstacleSource, RejectsBadParams) {
  ObstacleParams p;
  p.range_m = 0.0;
  EXPECT_THROW(ObstacleSource{p}, std::invalid_argument);
  EXPECT_THROW(rectangleFence({0, 0}, {1, 1}, 0.0), std::invalid_argument);
  EXPECT_THROW(rectangleFence({1, 0}, {0, 1}, 0.1), std::invalid_argument);
}

TEST(NavObstacleSource, FenceSurroundsTheRectangle) {
  const auto fence = rectangleFence({0, -1}, {4, 1}, 0.5);
  EXPECT_EQ(fence.size(), 24u);  // perimeter 12 m every 0.5 m
  for (const auto& p : fence) {
    const bool on_x = std::abs(p.x()) < 1e-9 || std::abs(p.x() - 4) < 1e-9;
    const bool on_y = std::abs(p.y() + 1) < 1e-9 || std::abs(p.y() - 1) < 1e-9;
    EXPECT_TRUE(on_x || on_y) << p.transpose();
  }
}

// The CRobot2NavInterface MRPT's navigator calls: pose from the base, obstacles in the robot
// frame at the configured height.
TEST(NavUpdNavInterface, SenseObstaclesGivesRobotFramePoints) {
  const auto grid = gridWith({{3.04, 1.06}});
  ObstacleParams p;
  p.point_height_m = 0.25;
  ObstacleSource src(p);
  src.setMap(&grid);
  SimulatedDiffDrive base({1.0, 1.0, kPi / 2});
  UpdNavInterface bridge(base, src);
  mrpt::maps::CSimplePointsMap obstacles;
  mrpt::system::TTimeStamp t;
  ASSERT_TRUE(bridge.senseObstacles(obstacles, t));
  ASSERT_EQ(obstacles.size(), 1u);
  float x, y, z;
  obstacles.getPoint(0, x, y, z);
  EXPECT_NEAR(x, 0.05, 1e-5);
  EXPECT_NEAR(y, -2.05, 1e-5);
  EXPECT_NEAR(z, 0.25, 1e-6);
  EXPECT_EQ(bridge.lastObstacleCount(), 1u);

  mrpt::math::TPose2D pose, odo;
  mrpt::math::TTwist2D vel;
  std::string frame;
  ASSERT_TRUE(bridge.getCurrentPoseAndSpeeds(pose, vel, t, odo, frame));
  EXPECT_NEAR(pose.x, 1.0, 1e-12);
  EXPECT_NEAR(pose.y, 1.0, 1e-12);
  EXPECT_NEAR(pose.phi, kPi / 2, 1e-12);
}

TEST(NavUpdNavInterface, VelocityCommandsReachTheBase) {
  ObstacleSource src;
  SimulatedDiffDrive base({0.0, 0.0, 0.0}, SimulatedBaseParams{0.0, 0.0});
  UpdNavInterface bridge(base, src);
  mrpt::kinematics::CVehicleVelCmd_DiffDriven cmd;
  cmd.lin_vel = 0.3;
  cmd.ang_vel = 0.0;
  ASSERT_TRUE(bridge.changeSpeeds(cmd));
  base.advance(2.0);
  EXPECT_NEAR(base.pose().x_m, 0.6, 0.01);
  EXPECT_NEAR(base.pose().y_m, 0.0, 1e-6);
  ASSERT_TRUE(bridge.stop(false));
  base.advance(1.0);
  EXPECT_NEAR(base.pose().x_m, 0.6, 0.01);
  EXPECT_NEAR(bridge.getNavigationTime(), 3.0, 1e-3);
}

}  // namespace
}  // namespace upd::nav
