// Step edges on the grid's elevations (upd/maps/step_edges.h): a low step's edge is found, a
// smooth ramp of any drivable slope and rough ground are not.
#include "upd/maps/step_edges.h"
#include "upd/maps/traversability_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>

using upd::maps::findStepEdges;
using upd::maps::GridParams;
using upd::maps::StepEdgeParams;
using upd::maps::TraversabilityGrid;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A fixed 10 x 10 m grid of 0.1 m cells round the origin whose cells all hold 20 points at the
// height h(x, y) of their centre.
TraversabilityGrid gridOf(const std::function<double(double, double)>& h) {
  GridParams g;
  g.cell_size_m = 0.1;
  g.extent_m = 10.0;
  g.follow_robot = false;
  TraversabilityGrid grid(g);
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    for (int cx = 0; cx < grid.sizeX(); ++cx) {
      const Eigen::Vector2d c = grid.cellCenter(cx, cy);
      auto& cell = grid.at(cx, cy);
      cell.hits = 20;
      cell.logodds_nontrav = -1.0f;
      cell.elevation_m = static_cast<float>(h(c.x(), c.y()));
      cell.elevation_max_m = cell.elevation_m;
    }
  }
  return grid;
}

StepEdgeParams params() {
  StepEdgeParams p;
  p.max_step_m = 0.05;
  p.range_m = 2.5;
  return p;
}

}  // namespace

TEST(StepEdges, SixCentimetreStepOnFlatGroundIsFound) {
  // A 6 cm platform beyond x = 1.03 m (inside a cell, as an edge usually is).
  const auto grid = gridOf([](double x, double) { return x > 1.03 ? 0.06 : 0.0; });
  const auto edges = findStepEdges(grid, {0.0, 0.0}, params());
  ASSERT_FALSE(edges.empty());
  for (const auto& e : edges) EXPECT_NEAR(e.x(), 1.03, 0.15) << "only cells at the edge";
  // Every cell row across the edge within range has an edge cell.
  bool on_axis = false;
  for (const auto& e : edges) on_axis = on_axis || std::abs(e.y()) < 0.1;
  EXPECT_TRUE(on_axis);
}

TEST(StepEdges, FourCentimetreStepIsDrivable) {
  const auto grid = gridOf([](double x, double) { return x > 1.03 ? 0.04 : 0.0; });
  EXPECT_TRUE(findStepEdges(grid, {0.0, 0.0}, params()).empty());
}

TEST(StepEdges, SmoothRampsUpToTwentyFiveDegreesAreNotEdges) {
  for (const double deg : {10.0, 20.0, 25.0}) {
    const double t = std::tan(deg * kPi / 180.0);
    // Flat, a ramp from x = 0.52 m rising at deg (foot crease), a flat top from 1.5 m higher
    // (top crease), seen along x and along a diagonal.
    const auto ramp = [t](double u) { return std::clamp(u - 0.52, 0.0, 1.0) * t; };
    const auto along_x = gridOf([&](double x, double) { return ramp(x); });
    EXPECT_TRUE(findStepEdges(along_x, {0.5, 0.0}, params()).empty()) << deg << " deg along x";
    const auto diagonal = gridOf([&](double x, double y) { return ramp((x + y) / std::sqrt(2.0)); });
    EXPECT_TRUE(findStepEdges(diagonal, {0.5, 0.0}, params()).empty()) << deg << " deg diagonal";
  }
}

TEST(StepEdges, RampSideTallerThanTheLimitIsFound) {
  // A 20 deg ramp 1 m wide (|y| < 0.5) rising along x from x = 0: its side at y = 0.5 is an edge
  // where the ramp stands taller than 5 cm (x > 0.14 m), not at its foot.
  const double t = std::tan(20.0 * kPi / 180.0);
  const auto grid = gridOf([t](double x, double y) {
    return std::abs(y) < 0.52 && x > 0.0 ? std::min(x, 1.0) * t : 0.0;
  });
  const auto edges = findStepEdges(grid, {0.0, 0.0}, params());
  bool side_high = false;
  for (const auto& e : edges) {
    EXPECT_GT(e.x(), 0.05) << "no edge at the ramp's foot";
    side_high = side_high || (std::abs(std::abs(e.y()) - 0.52) < 0.15 && e.x() > 0.3);
  }
  EXPECT_TRUE(side_high);
}

TEST(StepEdges, RoughGroundIsNotAnEdge) {
  // 1 cm waves of 1 m wavelength in two directions.
  const auto grid = gridOf([](double x, double y) {
    return 0.01 * std::sin(2 * kPi * x) + 0.01 * std::sin(2 * kPi * (0.6 * x + 0.8 * y) + 1.0);
  });
  EXPECT_TRUE(findStepEdges(grid, {0.0, 0.0}, params()).empty());
}

TEST(StepEdges, CellsWithTooFewPointsAndDisabledCheckFindNothing) {
  auto grid = gridOf([](double x, double) { return x > 1.03 ? 0.2 : 0.0; });
  StepEdgeParams off = params();
  off.enabled = false;
  EXPECT_TRUE(findStepEdges(grid, {0.0, 0.0}, off).empty());
  StepEdgeParams strict = params();
  strict.min_hits = 21;  // every cell holds 20 points
  EXPECT_TRUE(findStepEdges(grid, {0.0, 0.0}, strict).empty());
  StepEdgeParams far = params();
  far.range_m = 0.5;  // the edge is 1 m away
  EXPECT_TRUE(findStepEdges(grid, {0.0, 0.0}, far).empty());
}

TEST(StepEdges, BadParametersAreRejected) {
  StepEdgeParams p = params();
  p.max_step_m = 0.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = params();
  p.min_hits = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = params();
  p.range_m = -1.0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}
