// The grid's whole-run memory: cells that leave the rolling window are kept in compressed tiles
// and come back bit for bit; the whole run equals one big fixed grid fed the same frames; memory
// stays within the window plus the stated cost per tile.
#include "maps/frames.h"
#include "upd/maps/grid_fusion.h"
#include "upd/maps/traversability_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

namespace core = upd::core;

using upd::maps::FusionParams;
using upd::maps::GridCell;
using upd::maps::GridParams;
using upd::maps::integrateScan;
using upd::maps::TraversabilityGrid;
using upd::test::Frame;

namespace {

bool sameBits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// Every field bit for bit (NaN payloads included).
bool sameCell(const GridCell& a, const GridCell& b) {
  return sameBits(a.logodds_nontrav, b.logodds_nontrav) && sameBits(a.zeta_min, b.zeta_min) &&
         sameBits(a.zeta_mean, b.zeta_mean) && sameBits(a.slope_rad, b.slope_rad) &&
         sameBits(a.cost_mean, b.cost_mean) && sameBits(a.elevation_m, b.elevation_m) &&
         sameBits(a.elevation_max_m, b.elevation_max_m) && a.hits == b.hits &&
         a.zeta_count == b.zeta_count && a.slope_count == b.slope_count &&
         a.cost_count == b.cost_count &&
         std::memcmp(&a.last_seen_s, &b.last_seen_s, sizeof a.last_seen_s) == 0;
}

// n scored points within radius_m of the robot: mostly ground, some obstacles, some NaN zeta.
Frame randomFrame(std::mt19937& rng, double x, double y, double radius_m, int n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0), unit(0.0, 1.0);
  Frame f;
  while (static_cast<int>(f.x.size()) < n) {
    const double dx = radius_m * u(rng), dy = radius_m * u(rng);
    if (dx * dx + dy * dy > radius_m * radius_m) continue;
    const bool rock = unit(rng) < 0.15;
    const core::Label l = unit(rng) < 0.05 ? core::Label::Unknown
                          : rock           ? core::Label::NonTraversable
                                           : core::Label::Traversable;
    const float zeta = unit(rng) < 0.1 ? NAN : static_cast<float>(rock ? 0.8 : 0.99);
    f.add(static_cast<float>(x + dx), static_cast<float>(y + dy),
          static_cast<float>(0.3 * unit(rng)), l, zeta, static_cast<float>(0.2 * unit(rng)),
          static_cast<float>(unit(rng)));
  }
  return f;
}

GridParams rolling(double extent_m, double extent_y_m, int tile_cells) {
  GridParams p;
  p.cell_size_m = 0.1;
  p.extent_m = extent_m;
  p.extent_y_m = extent_y_m;
  p.follow_robot = true;
  p.tile_cells = tile_cells;
  return p;
}

void expectWithinStatedMemory(const TraversabilityGrid& g) {
  EXPECT_EQ(g.memoryBytes(), g.windowBytes() + g.storedTileBytes());
  EXPECT_LE(g.storedTileBytes(), g.storedTiles() * g.maxTileBytes());
}

}  // namespace

TEST(WholeRunGrid, RobotGoingOutAndComingBackGetsItsCellsBackBitForBit) {
  TraversabilityGrid g(rolling(8.0, 0.0, 16));
  std::mt19937 rng(3);
  for (int k = 0; k < 10; ++k) {
    integrateScan(g, randomFrame(rng, 0.2 * k, 0.0, 1.8, 400).view(), {0.2 * k, 0.0}, k,
                  FusionParams{});
  }
  const TraversabilityGrid before = g;  // the window at the start
  // 60 m out along x and back along y = 20 m, mapping all the way.
  double t = 100;
  for (double x = 2.0; x <= 60.0; x += 1.0, ++t) {
    integrateScan(g, randomFrame(rng, x, 20.0, 1.8, 200).view(), {x, 20.0}, t, FusionParams{});
    expectWithinStatedMemory(g);
  }
  EXPECT_GT(g.storedTiles(), 10u);
  EXPECT_FALSE(g.cellAt(0.05, 0.05) != nullptr);
  ASSERT_TRUE(g.moveTo({0.0, 0.0}));
  ASSERT_EQ(g.originI(), before.originI());
  ASSERT_EQ(g.originJ(), before.originJ());
  for (int cy = 0; cy < g.sizeY(); ++cy) {
    for (int cx = 0; cx < g.sizeX(); ++cx) {
      ASSERT_TRUE(sameCell(g.at(cx, cy), before.at(cx, cy))) << cx << "," << cy;
    }
  }
  // Revisited cells continue fusing onto their old evidence.
  const GridCell old = *g.cellAt(0.05, 0.05);
  ASSERT_GT(old.hits, 0u);
  Frame again;
  again.fillCell(0.0, 0.0, 0.1, 5, core::Label::Traversable);
  integrateScan(g, again.view(), {0.0, 0.0}, t, FusionParams{});
  EXPECT_EQ(g.cellAt(0.05, 0.05)->hits, old.hits + 5);
}

// Property: over random paths (fixed seeds) the whole run of the rolling window equals a single
// big fixed grid fed the same frames, cell for cell and bit for bit, and memory stays within the
// window plus the stated cost per kept tile. Square and oblong windows, tiles that do and do not
// divide the window.
TEST(WholeRunGrid, EqualsOneBigFixedGridFedTheSameFrames) {
  struct Case {
    double extent_m, extent_y_m;
    int tile_cells;
    unsigned seed;
  };
  for (const Case& c : {Case{8.0, 0.0, 16, 1}, Case{8.0, 6.0, 24, 2}, Case{6.0, 9.0, 8, 3}}) {
    SCOPED_TRACE(c.seed);
    TraversabilityGrid roll(rolling(c.extent_m, c.extent_y_m, c.tile_cells));
    GridParams fixed_p;
    fixed_p.cell_size_m = 0.1;
    fixed_p.extent_m = 70.0;
    fixed_p.follow_robot = false;
    TraversabilityGrid fixed(fixed_p);
    std::mt19937 rng(c.seed);
    std::uniform_real_distribution<double> turn(-0.8, 0.8), step(0.2, 1.5);
    // Points within 1.4 m of the robot: inside the window once it has moved (the robot is
    // within recenter_fraction of the smaller side, 1.5 m, of the window centre).
    double x = 0, y = 0, heading = 0;
    int moves = 0;
    for (int k = 0; k < 300; ++k) {
      heading += turn(rng);
      x += step(rng) * std::cos(heading);
      y += step(rng) * std::sin(heading);
      if (std::abs(x) > 25 || std::abs(y) > 25) heading += M_PI;  // turn back inside
      x = std::clamp(x, -28.0, 28.0), y = std::clamp(y, -28.0, 28.0);
      const Frame f = randomFrame(rng, x, y, 1.4, 150);
      const auto s = integrateScan(roll, f.view(), {x, y}, k, FusionParams{});
      ASSERT_EQ(s.points_outside, 0u) << "frame " << k;
      integrateScan(fixed, f.view(), {x, y}, k, FusionParams{});
      moves += s.window_moved;
      expectWithinStatedMemory(roll);
    }
    EXPECT_GT(moves, 30);
    const TraversabilityGrid whole = roll.wholeRun();
    EXPECT_FALSE(whole.params().follow_robot);
    std::size_t observed = 0;
    for (int cy = 0; cy < fixed.sizeY(); ++cy) {
      for (int cx = 0; cx < fixed.sizeX(); ++cx) {
        const GridCell& want = fixed.at(cx, cy);
        const std::int64_t gi = fixed.originI() + cx, gj = fixed.originJ() + cy;
        const bool inside = gi >= whole.originI() && gi < whole.originI() + whole.sizeX() &&
                            gj >= whole.originJ() && gj < whole.originJ() + whole.sizeY();
        if (!inside) {
          ASSERT_FALSE(want.observed()) << "observed cell " << gi << "," << gj << " not covered";
          continue;
        }
        observed += want.observed();
        const GridCell& got =
            whole.at(static_cast<int>(gi - whole.originI()), static_cast<int>(gj - whole.originJ()));
        ASSERT_TRUE(sameCell(got, want)) << "cell " << gi << "," << gj;
      }
    }
    EXPECT_GT(observed, 10000u);
    std::printf("window %.0f x %.0f m, %d-cell tiles: %zu tiles, %.0f bytes per tile (bound %zu)\n",
                c.extent_m, c.extent_y_m > 0 ? c.extent_y_m : c.extent_m, c.tile_cells,
                roll.storedTiles(),
                roll.storedTiles() ? double(roll.storedTileBytes()) / roll.storedTiles() : 0.0,
                roll.maxTileBytes());
  }
}

TEST(WholeRunGrid, WithoutKeepingTheWindowAloneIsBoundedAndTheRestIsDropped) {
  GridParams p = rolling(8.0, 0.0, 16);
  p.keep_outside_window = false;
  TraversabilityGrid g(p);
  std::mt19937 rng(5);
  for (int k = 0; k < 40; ++k) {
    integrateScan(g, randomFrame(rng, k, 0.0, 1.5, 100).view(), {double(k), 0.0}, k, FusionParams{});
  }
  EXPECT_EQ(g.storedTiles(), 0u);
  EXPECT_EQ(g.memoryBytes(), g.windowBytes());
  const TraversabilityGrid whole = g.wholeRun();
  EXPECT_GE(whole.xMin(), g.xMin());  // only what the window holds
}

TEST(WholeRunGrid, TileParametersAreValidated) {
  GridParams p;
  p.tile_cells = 4;
  EXPECT_THROW(TraversabilityGrid{p}, std::invalid_argument);
  p = GridParams{};
  p.extent_y_m = 0.05;
  EXPECT_THROW(TraversabilityGrid{p}, std::invalid_argument);
}
