// Recovery of a stalled robot: the manoeuvre never brings an obstacle point into the robot's
// shape (nor deeper into it), turns towards the route when there is room and reverses otherwise.
#include "upd/nav/recovery.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace upd::nav {
namespace {

constexpr double kHalfLength = 0.4, kHalfWidth = 0.275;  // the shipped navigator polygon

// Points along a straight wall from (x0, y0) to (x1, y1), every 5 cm.
void addWall(std::vector<Eigen::Vector2d>& pts, double x0, double y0, double x1, double y1) {
  const Eigen::Vector2d a(x0, y0), b(x1, y1);
  const int n = static_cast<int>(std::ceil((b - a).norm() / 0.05));
  for (int i = 0; i <= n; ++i) pts.push_back(a + (b - a) * (static_cast<double>(i) / n));
}

// The robot's pose after holding the command for t, from the origin of the robot frame.
Eigen::Vector3d poseAfter(const Twist2D& c, double t) {
  const double th = c.w_radps * t;
  if (std::abs(c.w_radps) < 1e-9) return {c.v_mps * t, 0.0, 0.0};
  return {c.v_mps / c.w_radps * std::sin(th), c.v_mps / c.w_radps * (1 - std::cos(th)), th};
}

double clearanceAlong(const std::vector<Eigen::Vector2d>& pts, const RecoveryMotion& m) {
  double worst = 1e9;
  for (double t = 0; t <= m.duration_s + 1e-9; t += 0.01) {
    const Eigen::Vector3d p = poseAfter(m.command, t);
    const double c = std::cos(p.z()), s = std::sin(p.z());
    for (const auto& q : pts) {
      const double dx = q.x() - p.x(), dy = q.y() - p.y();
      worst = std::min(worst, rectangleSignedDistance({c * dx + s * dy, -s * dx + c * dy},
                                                      kHalfLength, kHalfWidth));
    }
  }
  return worst;
}

TEST(RecoveryTest, RectangleSignedDistance) {
  EXPECT_NEAR(rectangleSignedDistance({0, 0}, 0.4, 0.2), -0.2, 1e-12);
  EXPECT_NEAR(rectangleSignedDistance({0.5, 0}, 0.4, 0.2), 0.1, 1e-12);
  EXPECT_NEAR(rectangleSignedDistance({0, -0.25}, 0.4, 0.2), 0.05, 1e-12);
  EXPECT_NEAR(rectangleSignedDistance({0.7, 0.6}, 0.4, 0.2), 0.5, 1e-12);  // from the corner
  EXPECT_NEAR(rectangleSignedDistance({0.4, 0.1}, 0.4, 0.2), 0.0, 1e-12);
}

TEST(RecoveryTest, FeasibleDurationStopsBeforeAnObstacle) {
  const std::vector<Eigen::Vector2d> ahead{{0.6, 0.0}};  // 0.2 m in front of the shape
  EXPECT_NEAR(feasibleDuration(ahead, kHalfLength, kHalfWidth, {0.1, 0.0}, 5.0), 2.0, 0.05);
  EXPECT_DOUBLE_EQ(feasibleDuration(ahead, kHalfLength, kHalfWidth, {-0.1, 0.0}, 5.0), 5.0);
  EXPECT_DOUBLE_EQ(feasibleDuration({}, kHalfLength, kHalfWidth, {0.0, 0.5}, 3.0), 3.0);
}

TEST(RecoveryTest, APointInsideTheShapeMayBeLeftNotEntered) {
  const std::vector<Eigen::Vector2d> inside{{0.35, 0.0}};  // 5 cm inside the front edge
  EXPECT_DOUBLE_EQ(feasibleDuration(inside, kHalfLength, kHalfWidth, {-0.15, 0.0}, 2.0), 2.0);
  EXPECT_LT(feasibleDuration(inside, kHalfLength, kHalfWidth, {0.15, 0.0}, 2.0), 0.05);
}

TEST(RecoveryTest, TurnsTowardsTheRouteInTheOpen) {
  const RecoveryParams p;
  const RecoveryMotion left = planRecovery({}, kHalfLength, kHalfWidth, 1.0, p);
  ASSERT_TRUE(left.feasible());
  EXPECT_DOUBLE_EQ(left.command.v_mps, 0.0);
  EXPECT_GT(left.command.w_radps, 0.0);
  EXPECT_NEAR(left.command.w_radps * left.duration_s, 1.0, 1e-6);
  const RecoveryMotion right = planRecovery({}, kHalfLength, kHalfWidth, -3.0, p);
  EXPECT_LT(right.command.w_radps, 0.0);
  EXPECT_NEAR(-right.command.w_radps * right.duration_s, p.max_turn_rad, 1e-6);
}

TEST(RecoveryTest, ReversesWhenFacingTheRouteOrWhenThereIsNoRoomToTurn) {
  const RecoveryParams p;
  // Facing the route already: a turn is not worth it.
  const RecoveryMotion open = planRecovery({}, kHalfLength, kHalfWidth, 0.1, p);
  ASSERT_TRUE(open.feasible());
  EXPECT_LT(open.command.v_mps, 0.0);
  // A corridor 5 cm wider than the shape on each side, blocked ahead: the corners would hit the
  // walls in a turn, the way back is open.
  std::vector<Eigen::Vector2d> corridor;
  addWall(corridor, -3.0, 0.325, 3.0, 0.325);
  addWall(corridor, -3.0, -0.325, 3.0, -0.325);
  addWall(corridor, 0.5, -0.3, 0.5, 0.3);
  const RecoveryMotion m = planRecovery(corridor, kHalfLength, kHalfWidth, 1.5, p);
  ASSERT_TRUE(m.feasible());
  EXPECT_LT(m.command.v_mps, 0.0);
  EXPECT_GE(clearanceAlong(corridor, m), -1e-3);
}

TEST(RecoveryTest, NoManoeuvreWhenBoxedIn) {
  std::vector<Eigen::Vector2d> box;
  addWall(box, -0.45, 0.3, 0.45, 0.3);
  addWall(box, -0.45, -0.3, 0.45, -0.3);
  addWall(box, 0.45, -0.3, 0.45, 0.3);
  addWall(box, -0.45, -0.3, -0.45, 0.3);
  EXPECT_FALSE(planRecovery(box, kHalfLength, kHalfWidth, 1.0, RecoveryParams{}).feasible());
}

// Property over random clutter: whatever is chosen keeps every point out of the shape that
// started out of it.
TEST(RecoveryTest, ChosenManoeuvreNeverEntersAnObstacle) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.2, 1.2), h(-3.1, 3.1);
  int feasible = 0;
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<Eigen::Vector2d> pts;
    while (pts.size() < 12) {
      const Eigen::Vector2d q(u(rng), u(rng));
      if (rectangleSignedDistance(q, kHalfLength, kHalfWidth) > 0.01) pts.push_back(q);
    }
    const RecoveryMotion m = planRecovery(pts, kHalfLength, kHalfWidth, h(rng), RecoveryParams{});
    if (!m.feasible()) continue;
    ++feasible;
    // Checked every 0.05 s: between checks a corner moves at most 0.5 rad/s * 0.05 s * 0.49 m.
    EXPECT_GE(clearanceAlong(pts, m), -0.013) << "trial " << trial;
  }
  EXPECT_GT(feasible, 20);
}

TEST(RecoveryTest, ParamsValidate) {
  RecoveryParams p;
  EXPECT_NO_THROW(p.validate());
  p.stall_time_s = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = {};
  p.min_turn_rad = p.max_turn_rad + 0.1;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace upd::nav
