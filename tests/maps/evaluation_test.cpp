// Scoring a traversability grid against a ground truth: precision and recall.
#include "upd/maps/evaluation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <stdexcept>

namespace core = upd::core;

namespace {

using upd::core::Label;
using upd::maps::evaluateGrid;
using upd::maps::GridParams;
using upd::maps::MapEvaluation;
using upd::maps::TraversabilityGrid;
using upd::maps::TruthLabelAt;

// A fixed 20 x 20 window of 0.1 m cells around the origin.
TraversabilityGrid makeGrid() {
  GridParams p;
  p.cell_size_m = 0.1;
  p.extent_m = 2.0;
  p.follow_robot = false;
  TraversabilityGrid grid(p);
  EXPECT_EQ(grid.sizeX(), 20);
  EXPECT_EQ(grid.sizeY(), 20);
  return grid;
}

// Marks cell (cx, cy) observed with the given label.
void observe(TraversabilityGrid& grid, int cx, int cy, core::Label label) {
  upd::maps::GridCell& c = grid.at(cx, cy);
  c.hits = 5;
  c.logodds_nontrav = label == core::Label::NonTraversable ? 2.f : -2.f;
}

// Every cell observed: NonTraversable where nontrav(cx, cy), else Traversable.
void observeAll(TraversabilityGrid& grid, const std::function<bool(int, int)>& nontrav) {
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    for (int cx = 0; cx < grid.sizeX(); ++cx) {
      observe(grid, cx, cy, nontrav(cx, cy) ? core::Label::NonTraversable : core::Label::Traversable);
    }
  }
}

// The truth: a wall along window column 10.
TruthLabelAt wallTruth(const TraversabilityGrid& grid) {
  return [&grid](double x, double y) {
    int cx = 0, cy = 0;
    if (!grid.cellIndex(x, y, cx, cy)) return core::Label::Unknown;
    return cx == 10 ? core::Label::NonTraversable : core::Label::Traversable;
  };
}

TEST(EvaluateGrid, PerfectMapHasPrecisionAndRecallOne) {
  TraversabilityGrid grid = makeGrid();
  observeAll(grid, [](int cx, int) { return cx == 10; });
  for (const double tolerance_m : {0.0, 0.5}) {
    const MapEvaluation e = evaluateGrid(grid, wallTruth(grid), tolerance_m);
    EXPECT_EQ(e.map_non_traversable, 20u);
    EXPECT_EQ(e.map_non_traversable_matched, 20u);
    EXPECT_EQ(e.truth_non_traversable, 20u);
    EXPECT_EQ(e.truth_non_traversable_found, 20u);
    EXPECT_DOUBLE_EQ(e.precision(), 1.0);
    EXPECT_DOUBLE_EQ(e.recall(), 1.0);
  }
}

// Half the wall found (10 true positives, 10 misses) and 5 false alarms at column 15.
TEST(EvaluateGrid, KnownConfusionGivesItsPrecisionAndRecall) {
  TraversabilityGrid grid = makeGrid();
  observeAll(grid, [](int cx, int cy) { return (cx == 10 && cy < 10) || (cx == 15 && cy < 5); });
  const MapEvaluation e = evaluateGrid(grid, wallTruth(grid), 0.0);
  EXPECT_EQ(e.map_non_traversable, 15u);
  EXPECT_EQ(e.map_non_traversable_matched, 10u);
  EXPECT_EQ(e.truth_non_traversable, 20u);
  EXPECT_EQ(e.truth_non_traversable_found, 10u);
  EXPECT_DOUBLE_EQ(e.precision(), 10.0 / 15.0);
  EXPECT_DOUBLE_EQ(e.recall(), 0.5);
}

// A wall mapped one cell off misses everything cell by cell and matches within one cell.
TEST(EvaluateGrid, ToleranceForgivesAnOffsetWithinIt) {
  TraversabilityGrid grid = makeGrid();
  observeAll(grid, [](int cx, int) { return cx == 11; });
  const MapEvaluation strict = evaluateGrid(grid, wallTruth(grid), 0.0);
  EXPECT_DOUBLE_EQ(strict.precision(), 0.0);
  EXPECT_DOUBLE_EQ(strict.recall(), 0.0);
  const MapEvaluation tolerant = evaluateGrid(grid, wallTruth(grid), 0.1);
  EXPECT_DOUBLE_EQ(tolerant.precision(), 1.0);
  EXPECT_DOUBLE_EQ(tolerant.recall(), 1.0);
  const MapEvaluation too_far = evaluateGrid(grid, wallTruth(grid), 0.09);
  EXPECT_DOUBLE_EQ(too_far.precision(), 0.0);
}

// Cells the map never observed and cells outside the truth are not scored.
TEST(EvaluateGrid, UnobservedCellsAndCellsOutsideTheTruthAreNotScored) {
  TraversabilityGrid grid = makeGrid();
  const MapEvaluation empty = evaluateGrid(grid, wallTruth(grid), 0.0);
  EXPECT_EQ(empty.map_non_traversable, 0u);
  EXPECT_EQ(empty.truth_non_traversable, 0u);
  EXPECT_TRUE(std::isnan(empty.precision()));
  EXPECT_TRUE(std::isnan(empty.recall()));

  for (int cy = 0; cy < 4; ++cy) observe(grid, 10, cy, core::Label::NonTraversable);
  observe(grid, 3, 3, core::Label::NonTraversable);
  const TruthLabelAt left_half_unknown = [&grid](double x, double y) {
    int cx = 0, cy = 0;
    grid.cellIndex(x, y, cx, cy);
    return cx < 5 ? core::Label::Unknown : wallTruth(grid)(x, y);
  };
  const MapEvaluation e = evaluateGrid(grid, left_half_unknown, 0.0);
  EXPECT_EQ(e.map_non_traversable, 4u);  // not the cell at (3, 3): no truth there
  EXPECT_EQ(e.truth_non_traversable, 4u);
  EXPECT_DOUBLE_EQ(e.precision(), 1.0);
  EXPECT_DOUBLE_EQ(e.recall(), 1.0);
  EXPECT_THROW(evaluateGrid(grid, wallTruth(grid), -0.1), std::invalid_argument);
}

}  // namespace
