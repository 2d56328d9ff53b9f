// The loop's stall recovery stays on ground the map has observed: a robot stalled at the end of a
// dead end whose ground behind it the map has never seen does not reverse onto that ground,
// and does when RecoveryParams::into_unobserved allows it.
#include "upd/nav/nav_config.h"
#include "upd/nav/navigation_loop.h"
#include "upd/nav/route_planner.h"

#include <mrpt/core/Clock.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

namespace upd::nav {
namespace {

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config";

struct DeadEndRun {
  int recoveries = 0;
  double min_x_m = 0.0;  ///< the robot's rearmost position [m]
};

// The robot at the origin facing +x in a dead end (walls 5 cm beyond the navigator's shape on
// each side, one ahead), the goal beyond the end wall; no camera frame, so the map has observed
// nothing. The navigator cannot get past the walls: the robot stalls. unobserved_behind_m: the
// obstacle source's unobserved ground behind the robot (0: none, MRPT's backward PTG free).
DeadEndRun runDeadEnd(bool into_unobserved, double end_wall_x_m = 0.5,
                      double unobserved_behind_m = 0.0) {
  NavConfig config = loadNavConfig(kConfig + "/dune-kinect.ini", kConfig + "/dune-nav.ini");
  config.recovery.into_unobserved = into_unobserved;
  config.obstacles.unobserved_behind_m = unobserved_behind_m;
  config.recovery.stall_time_s = 2.0;
  config.navigator.no_progress_timeout_s = 20.0;
  const mrpt::Clock::Source previous = mrpt::Clock::getActiveClock();
  mrpt::Clock::setActiveClock(mrpt::Clock::Simulated);
  mrpt::Clock::setSimulatedTime(mrpt::Clock::fromDouble(1.0e9));
  SimulatedDiffDrive base(Pose2D{0.0, 0.0, 0.0}, config.base);
  NavigationLoop loop(base, config, core::ObstacleDetector::Upd);
  std::vector<Eigen::Vector2d> walls = rectangleFence({-4.0, -4.0}, {4.0, 4.0}, 0.05);
  for (double x = -0.2; x <= end_wall_x_m + 0.1; x += 0.05) {
    walls.emplace_back(x, 0.33);
    walls.emplace_back(x, -0.33);
  }
  for (double y = -0.33; y <= 0.33; y += 0.05) walls.emplace_back(end_wall_x_m, y);
  loop.setFixedObstacles(walls);
  loop.navigateTo({end_wall_x_m + 1.5, 0.0});
  DeadEndRun run;
  for (int k = 0; k < 300; ++k) {
    mrpt::Clock::setSimulatedTime(mrpt::Clock::fromDouble(1.0e9 + base.timeS()));
    if (loop.step() != NavState::Navigating) break;
    base.advance(config.loop.control_period_s);
    run.min_x_m = std::min(run.min_x_m, base.pose().x_m);
  }
  run.recoveries = loop.recoveries();
  loop.finish();
  mrpt::Clock::setActiveClock(previous);
  return run;
}

TEST(NavRecoveryLoop, NoReverseOntoGroundTheMapHasNotSeen) {
  // MRPT's backward PTG backs the robot partly out of the dead end, where it stalls: every
  // manoeuvre from there would cross unknown ground, so the loop drives none.
  const DeadEndRun blind = runDeadEnd(false);
  EXPECT_EQ(blind.recoveries, 0);
  // The same dead end when unobserved ground counts as free: the loop backs out further.
  const DeadEndRun reckless = runDeadEnd(true);
  EXPECT_GE(reckless.recoveries, 1);
  EXPECT_LT(reckless.min_x_m, blind.min_x_m - 0.1);
}

// Ground the robot has driven on held it: a recovery may drive there again though the camera
// never saw it. In a dead end 2 m long the robot drives in, stalls at the end and backs out
// along its own tracks, with or without the unobserved ground behind it as obstacles.
TEST(NavRecoveryLoop, DrivenGroundCountsAsObserved) {
  EXPECT_GE(runDeadEnd(false, 2.0).recoveries, 1);
  EXPECT_GE(runDeadEnd(false, 2.0, 1.0).recoveries, 1);
}

// MRPT's own backward PTG: in the short dead end it backs the robot out over ground no frame
// observed; with ObstacleParams::unobserved_behind_m that ground is an obstacle and it does not.
TEST(NavRecoveryLoop, NavigatorDoesNotReverseOntoUnobservedGroundBehind) {
  EXPECT_LT(runDeadEnd(false, 0.5, 0.0).min_x_m, -0.3);
  EXPECT_GT(runDeadEnd(false, 0.5, 1.0).min_x_m, -0.05);
}

}  // namespace
}  // namespace upd::nav
