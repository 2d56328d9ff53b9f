// Step edges and bumps on the grid's elevations (upd/maps/step_edges.h): a low step's edge is
// found, a smooth ramp of any drivable slope and rough ground are not; a dome-shaped rock taller
// than the step limit is marked out to its foot and the truth's border beyond it, a pebble, a
// plane, a ramp, a platform and rough ground are not.
#include "upd/maps/step_edges.h"
#include "upd/maps/traversability_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

using upd::maps::findBumps;
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
      cell.zeta_min = 1.0f;  // the UPD read every cell smooth
    }
  }
  return grid;
}

// The same with every cell at the mean of h over a 4 x 4 lattice inside it (as the cell's
// points average a rock's flank).
TraversabilityGrid gridOfMeans(const std::function<double(double, double)>& h) {
  return gridOf([&](double x, double y) {
    double sum = 0.0;
    for (int j = 0; j < 4; ++j) {
      for (int i = 0; i < 4; ++i) sum += h(x - 0.0375 + 0.025 * i, y - 0.0375 + 0.025 * j);
    }
    return sum / 16.0;
  });
}

// A half-ellipsoid rock as upd::sim::Rock: height h at (cx, cy), radii (a along yaw, b across).
struct Dome {
  double cx, cy, a, b, yaw, h;
  // (u/a)^2 + (v/b)^2 at (x, y).
  double q(double x, double y) const {
    const double dx = x - cx, dy = y - cy;
    const double u = std::cos(yaw) * dx + std::sin(yaw) * dy;
    const double v = -std::sin(yaw) * dx + std::cos(yaw) * dy;
    return (u / a) * (u / a) + (v / b) * (v / b);
  }
  double height(double x, double y) const {
    const double qq = q(x, y);
    return qq < 1.0 ? h * std::sqrt(1.0 - qq) : 0.0;
  }
  // Inside the ellipse grown by g on both radii (the truth's rock with its border: g = 0.05).
  bool within(double x, double y, double g) const {
    const double dx = x - cx, dy = y - cy;
    const double u = std::cos(yaw) * dx + std::sin(yaw) * dy;
    const double v = -std::sin(yaw) * dx + std::cos(yaw) * dy;
    return (u / (a + g)) * (u / (a + g)) + (v / (b + g)) * (v / (b + g)) <= 1.0;
  }
};

bool contains(const std::vector<Eigen::Vector2d>& cells, const Eigen::Vector2d& c) {
  for (const auto& e : cells) {
    if ((e - c).norm() < 1e-6) return true;
  }
  return false;
}

StepEdgeParams params() {
  StepEdgeParams p;
  p.bumps = true;
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

TEST(Bumps, LowDomeRocksAreMarkedToTheirFootAndTheBorderBeyond) {
  // Rocks 7 and 12 cm tall, 0.15-0.4 m radii, on flat ground and on a 15 deg slope: every cell
  // whose centre lies on the rock or within the truth's 5 cm border round it is marked, none far
  // beyond.
  const double slope = std::tan(15.0 * kPi / 180.0);
  for (const Dome d : {Dome{1.0, 0.3, 0.3, 0.2, 0.5, 0.07}, Dome{-0.8, 1.1, 0.4, 0.35, 1.2, 0.12},
                       Dome{0.6, -1.2, 0.15, 0.18, 0.0, 0.07}}) {
    for (const double tilt : {0.0, slope}) {
      const auto grid = gridOfMeans([&](double x, double y) { return tilt * x + d.height(x, y); });
      const auto bumps = findBumps(grid, {0.0, 0.0}, params());
      int inside = 0;
      for (int cy = 0; cy < grid.sizeY(); ++cy) {
        for (int cx = 0; cx < grid.sizeX(); ++cx) {
          const Eigen::Vector2d c = grid.cellCenter(cx, cy);
          if (!d.within(c.x(), c.y(), 0.05)) continue;
          ++inside;
          EXPECT_TRUE(contains(bumps, c)) << "rock at (" << d.cx << ", " << d.cy << ") h " << d.h
                                          << " tilt " << tilt << ": cell " << c.transpose()
                                          << " inside its foot + 5 cm is not marked";
        }
      }
      EXPECT_GT(inside, 3);
      for (const auto& b : bumps) {
        EXPECT_TRUE(d.within(b.x(), b.y(), 0.2)) << "a marked cell " << b.transpose()
                                                 << " lies far beyond the rock";
      }
    }
  }
}

TEST(Bumps, PebblesPlanesRampsPlatformsAndRoughGroundAreNoBumps) {
  const double t20 = std::tan(20.0 * kPi / 180.0);
  const auto ramp = [t20](double u) { return std::clamp(u - 0.52, 0.0, 1.0) * t20; };
  const std::vector<std::pair<const char*, std::function<double(double, double)>>> scenes = {
      {"4 cm pebble",
       [](double x, double y) { return Dome{1.0, 0.3, 0.2, 0.2, 0.0, 0.04}.height(x, y); }},
      {"20 deg plane", [t20](double x, double y) { return t20 * (0.6 * x + 0.8 * y); }},
      {"20 deg ramp with a flat top", [&](double x, double) { return ramp(x); }},
      {"ramp bump 1.2 m wide", [&](double x, double y) {
         return std::abs(y) < 0.6 ? std::min(ramp(x), ramp(3.0 - x)) : 0.0;
       }},
      {"15 cm platform 2 x 2 m", [](double x, double y) {
         return std::abs(x - 1.5) < 1.0 && std::abs(y) < 1.0 ? 0.15 : 0.0;
       }},
      {"8 cm step", [](double x, double) { return x > 1.03 ? 0.08 : 0.0; }},
      {"ditch 0.6 m wide, 20 cm deep",
       [](double x, double) { return std::abs(x - 1.2) < 0.3 ? -0.2 : 0.0; }},
      {"1 cm waves", [](double x, double y) {
         return 0.01 * std::sin(2 * kPi * x) + 0.01 * std::sin(2 * kPi * (0.6 * x + 0.8 * y) + 1.0);
       }},
  };
  for (const auto& [name, h] : scenes) {
    EXPECT_TRUE(findBumps(gridOfMeans(h), {0.0, 0.0}, params()).empty()) << name;
  }
}

TEST(Bumps, TheBorderReachesBumpBorderMetresBeyondTheBumpsCells) {
  // The body: the cells standing bump_edge_m above the ground; the border: cells whose centre
  // lies within bump_border_m of a body cell's centre, and no others.
  const Dome d{1.0, 0.3, 0.3, 0.2, 0.5, 0.07};
  const auto grid = gridOfMeans([&](double x, double y) { return d.height(x, y); });
  for (const double border : {0.0, 0.1, 0.15}) {
    StepEdgeParams p = params();
    p.bump_border_m = border;
    const auto bumps = findBumps(grid, {0.0, 0.0}, p);
    std::vector<Eigen::Vector2d> body;
    for (int cy = 0; cy < grid.sizeY(); ++cy) {
      for (int cx = 0; cx < grid.sizeX(); ++cx) {
        if (grid.at(cx, cy).elevation_m > p.bump_edge_m) body.push_back(grid.cellCenter(cx, cy));
      }
    }
    ASSERT_GE(body.size(), 4u);
    for (const auto& c : body) EXPECT_TRUE(contains(bumps, c)) << border << ": " << c.transpose();
    for (const auto& b : bumps) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const auto& c : body) nearest = std::min(nearest, (b - c).norm());
      EXPECT_LE(nearest, border + 1e-6) << border << ": " << b.transpose();
    }
    // Every cell within the border of the body is marked.
    for (int cy = 0; cy < grid.sizeY(); ++cy) {
      for (int cx = 0; cx < grid.sizeX(); ++cx) {
        const Eigen::Vector2d q = grid.cellCenter(cx, cy);
        for (const auto& c : body) {
          if ((q - c).norm() <= border + 1e-6) {
            EXPECT_TRUE(contains(bumps, q)) << border << ": " << q.transpose();
            break;
          }
        }
      }
    }
  }
}

TEST(Bumps, DisabledCheckAndUnseenGroundFindNothing) {
  const Dome d{1.0, 0.3, 0.3, 0.2, 0.5, 0.1};
  auto grid = gridOfMeans([&](double x, double y) { return d.height(x, y); });
  StepEdgeParams off = params();
  off.bumps = false;
  EXPECT_TRUE(findBumps(grid, {0.0, 0.0}, off).empty());
  off = params();
  off.enabled = false;
  EXPECT_TRUE(findBumps(grid, {0.0, 0.0}, off).empty());
  StepEdgeParams strict = params();
  strict.min_hits = 21;  // every cell holds 20 points: no ground known
  EXPECT_TRUE(findBumps(grid, {0.0, 0.0}, strict).empty());
  ASSERT_FALSE(findBumps(grid, {0.0, 0.0}, params()).empty());
  // The UPD saw an edge on the rock (or never scored it): the bump is the UPD's to mark.
  for (const float zeta : {0.9f, std::numeric_limits<float>::quiet_NaN()}) {
    grid.cellAt(1.0, 0.3)->zeta_min = zeta;
    EXPECT_TRUE(findBumps(grid, {0.0, 0.0}, params()).empty()) << zeta;
  }
}

TEST(Bumps, BadParametersAreRejected) {
  const auto expectRejected = [](StepEdgeParams p, const char* key) {
    try {
      p.validate();
      ADD_FAILURE() << key << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  };
  StepEdgeParams p = params();
  p.bump_height_m = 0.0;
  expectRejected(p, "bump_height_m");
  p = params();
  p.bump_edge_m = 0.06;  // above bump_height_m
  expectRejected(p, "bump_edge_m");
  p = params();
  p.bump_ring_outer_m = p.bump_ring_inner_m;
  expectRejected(p, "bump_ring_outer_m");
  p = params();
  p.bump_ring_inner_m = -0.1;
  expectRejected(p, "bump_ring_inner_m");
  p = params();
  p.bump_fit_tolerance_m = 0.0;
  expectRejected(p, "bump_fit_tolerance_m");
  p = params();
  p.bump_min_inliers = 1.5;
  expectRejected(p, "bump_min_inliers");
  p = params();
  p.bump_min_zeta = -0.5;
  expectRejected(p, "bump_min_zeta");
  p = params();
  p.bump_border_m = -0.1;
  expectRejected(p, "bump_border_m");
}
