// Recovery of a stalled robot: the manoeuvre never brings an obstacle point into the robot's
// shape (nor deeper into it), nor ground the map has not observed, turns towards the route when
// there is room and reverses otherwise.
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

// Centres of 10 cm cells over [x0, x1] x [y0, y1] (robot frame): ground the map has not observed.
std::vector<Eigen::Vector2d> cellCentres(double x0, double x1, double y0, double y1) {
  std::vector<Eigen::Vector2d> out;
  for (double y = y0 + 0.05; y < y1; y += 0.1) {
    for (double x = x0 + 0.05; x < x1; x += 0.1) out.emplace_back(x, y);
  }
  return out;
}

// The ground behind the robot has never been observed (a forward-looking camera): no reverse
// drives onto it, however open it may be.
TEST(RecoveryTest, NoReverseOntoUnobservedGround) {
  const RecoveryParams p;  // into_unobserved = false
  const auto behind = cellCentres(-1.5, -0.4, -1.5, 1.5);
  EXPECT_FALSE(planRecovery({}, behind, kHalfLength, kHalfWidth, 0.1, p).feasible());
  // Observed and free: the full reverse.
  const RecoveryMotion open = planRecovery({}, {}, kHalfLength, kHalfWidth, 0.1, p);
  ASSERT_TRUE(open.feasible());
  EXPECT_LT(open.command.v_mps, 0.0);
  EXPECT_NEAR(-open.command.v_mps * open.duration_s, p.reverse_distance_m, 1e-6);
  // Unobserved from 0.2 m behind the shape on (cell centres 0.25 m behind): a shorter reverse.
  const auto far_behind = cellCentres(-1.5, -0.6, -1.5, 1.5);
  const RecoveryMotion shorter = planRecovery({}, far_behind, kHalfLength, kHalfWidth, 0.1, p);
  ASSERT_TRUE(shorter.feasible());
  EXPECT_LT(shorter.command.v_mps, 0.0);
  EXPECT_GE(-shorter.command.v_mps * shorter.duration_s, p.min_reverse_m);
  EXPECT_LT(-shorter.command.v_mps * shorter.duration_s, 0.3);
  EXPECT_GE(clearanceAlong(far_behind, shorter), -1e-3);
  // into_unobserved: unknown ground counts as free, the full reverse again.
  RecoveryParams into = p;
  into.into_unobserved = true;
  const RecoveryMotion blind = planRecovery({}, behind, kHalfLength, kHalfWidth, 0.1, into);
  ASSERT_TRUE(blind.feasible());
  EXPECT_NEAR(-blind.command.v_mps * blind.duration_s, p.reverse_distance_m, 1e-6);
}

// A turn in place sweeps the corners over the ground around the robot: unobserved ground there
// stops it too. The ground under the robot's shape is not in the way (the robot stands on it).
TEST(RecoveryTest, TurnsStayOnObservedGround) {
  const RecoveryParams p;
  std::vector<Eigen::Vector2d> unknown_around;
  for (const auto& c : cellCentres(-1.5, 1.5, -1.5, 1.5)) {
    if (rectangleSignedDistance(c, kHalfLength, kHalfWidth) > 0.0) unknown_around.push_back(c);
  }
  EXPECT_FALSE(planRecovery({}, unknown_around, kHalfLength, kHalfWidth, 1.0, p).feasible());
  const auto under = cellCentres(-0.4, 0.4, -0.2, 0.2);
  const RecoveryMotion turn = planRecovery({}, under, kHalfLength, kHalfWidth, 1.0, p);
  ASSERT_TRUE(turn.feasible());
  EXPECT_DOUBLE_EQ(turn.command.v_mps, 0.0);
  EXPECT_NEAR(turn.command.w_radps * turn.duration_s, 1.0, 1e-6);
  RecoveryParams into = p;
  into.into_unobserved = true;
  EXPECT_TRUE(planRecovery({}, unknown_around, kHalfLength, kHalfWidth, 1.0, into).feasible());
}

TEST(RecoveryTest, ReachCoversTheShapeAndTheReverse) {
  const RecoveryParams p;
  EXPECT_NEAR(recoveryReach(0.3, 0.4, p, 0.1), 0.5 + p.reverse_distance_m + 0.1, 1e-12);
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
