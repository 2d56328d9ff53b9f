// The simulated run: its route (planned on the ground truth with the one grid planner) keeps
// the clearance, reaches the goal and comes back, climbs the ramp nose up; an unreachable goal
// is an error naming the world; the truth written beside the rawlog reads back as the world's
// truth raster.
#include "upd/io/ros_map.h"
#include "upd/mrpt_bridge/simulated_run.h"
#include "upd/sim/terrain.h"
#include "upd/sim/truth_raster.h"

#include "temp_dir.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>

namespace core = upd::core;

namespace upd::mrpt_bridge {
namespace {

// Distance from p to the nearest NonTraversable cell centre of the raster.
double distanceToObstacle(const sim::TruthRaster& t, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (int iy = 0; iy < t.sizeY(); ++iy) {
    for (int ix = 0; ix < t.sizeX(); ++ix) {
      if (t.at(ix, iy) == core::Label::NonTraversable) {
        best = std::min(best, (t.cellCenter(ix, iy) - p).norm());
      }
    }
  }
  return best;
}

TEST(SimulatedRoute, KeepsTheClearanceReachesTheGoalAndComesBack) {
  const sim::WorldSpec world = sim::makeWorld("mixed");
  const SimulationParams p;
  const std::vector<RoutePose> route = planSimulatedRoute(world, p);
  ASSERT_GT(route.size(), 50u);
  const auto xy = [](const RoutePose& r) {
    return Eigen::Vector2d(r.pose_world_robot.translation().head<2>());
  };
  EXPECT_LT((xy(route.front()) - world.start_xy_yaw.head<2>()).norm(), 1e-9);
  EXPECT_LT((xy(route.back()) - world.start_xy_yaw.head<2>()).norm(), 1e-9);
  double closest_to_goal = 1e9;
  const sim::TruthRaster truth(world.terrain, 0.05);
  for (std::size_t k = 0; k < route.size(); ++k) {
    closest_to_goal = std::min(closest_to_goal, (xy(route[k]) - world.goal_xy).norm());
    // The planner's cells (0.1 m) keep clearance_m between centres: a pose may sit half a
    // cell's diagonal closer, and the finer raster's cells a quarter cell.
    EXPECT_GE(distanceToObstacle(truth, xy(route[k])), p.clearance_m - 0.071 - 0.036) << k;
    if (k > 0) {
      EXPECT_GE(route[k].t_s, route[k - 1].t_s);
      EXPECT_LE((xy(route[k]) - xy(route[k - 1])).norm(), 1.5 * p.frame_spacing_m);
    }
  }
  EXPECT_LT(closest_to_goal, 1e-9);
}

TEST(SimulatedRoute, ClimbsTheRampNoseUpOntoThePlatform) {
  const sim::WorldSpec world = sim::makeWorld("ramp");
  SimulationParams p;
  p.return_to_start = false;
  const std::vector<RoutePose> route = planSimulatedRoute(world, p);
  ASSERT_FALSE(route.empty());
  EXPECT_NEAR(route.back().pose_world_robot.translation().z(), 0.3, 1e-6);  // on the platform
  double max_nose_up = 0;
  for (const RoutePose& r : route) {
    max_nose_up = std::max(max_nose_up, std::asin(r.pose_world_robot.linear()(2, 0)));
  }
  // Up the 20 deg ramp (perhaps not square to it): nose up, never steeper than the ramp.
  EXPECT_GT(max_nose_up, 10.0 * core::kDegToRad);
  EXPECT_LE(max_nose_up, 20.0 * core::kDegToRad + 1e-9);
}

TEST(SimulatedRoute, AnUnreachableGoalIsAnErrorNamingTheWorld) {
  const sim::WorldSpec world = sim::makeWorld("trapped");
  try {
    planSimulatedRoute(world, SimulationParams{});
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(world.description), std::string::npos) << e.what();
  }
  SimulationParams bad;
  bad.body.track_m = 1.0;
  EXPECT_THROW(planSimulatedRoute(sim::makeWorld("mixed"), bad), std::invalid_argument);
}

TEST(SimulatedRun, WritesTheRawlogPosesAndTheTruthRaster) {
  const test::TempDir dir;
  const sim::WorldSpec world = sim::makeWorld("mixed");
  const SimulationParams p;
  const SimulationSummary s = simulateRun(world, p, dir.file("run.rawlog"), 3);
  EXPECT_EQ(s.frames, 3u);
  EXPECT_TRUE(std::filesystem::exists(s.rawlog_path));
  EXPECT_EQ(s.poses_path, dir.file("run.gt.tum"));
  std::ifstream poses(s.poses_path);
  std::string line;
  int lines = 0;
  while (std::getline(poses, line)) lines += !line.empty() && line[0] != '#';
  EXPECT_EQ(lines, 3);
  EXPECT_EQ(s.truth_yaml_path, dir.file("run.truth.yaml"));
  const io::RosMap read = io::readRosMap(s.truth_yaml_path);
  const sim::TruthRaster truth(world.terrain, p.truth_cell_m);
  EXPECT_EQ(read.width, truth.sizeX());
  EXPECT_EQ(read.height, truth.sizeY());
  EXPECT_DOUBLE_EQ(read.resolution_m, p.truth_cell_m);
  EXPECT_TRUE(read.origin_xy.isApprox(truth.origin()));
  EXPECT_EQ(read.labels, truth.labels());
  EXPECT_EQ(read.labelAt(7.25, -2.0), core::Label::NonTraversable);  // in the ditch
  EXPECT_EQ(read.labelAt(1.0, 0.0), core::Label::Traversable);       // the start
}

}  // namespace
}  // namespace upd::mrpt_bridge
