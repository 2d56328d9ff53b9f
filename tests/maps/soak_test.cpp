// A soak test of the maps: 10,000 generated frames of a robot lapping a 190 m circular course
// (21 laps). Once the course has been seen the maps' memory stays flat (the window, the box and
// the same kept tiles), and so does the process's peak memory; the maps written at the end
// equal ones built in two halves with a save to a file (.ot, grid state) and a reload between.
#include "maps/frames.h"
#include "sanitizer.h"
#include "temp_dir.h"
#include "upd/maps/grid_fusion.h"
#include "upd/maps/grid_state.h"
#include "upd/maps/traversability_grid.h"
#include "upd/maps/traversability_octree.h"

#include <gtest/gtest.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <tuple>

namespace core = upd::core;

using upd::maps::FusionParams;
using upd::maps::GridParams;
using upd::maps::OctreeParams;
using upd::maps::TraversabilityGrid;
using upd::maps::TraversabilityOcTree;
using upd::test::Frame;

namespace {

// The soak measures memory, not speed: on one thread its thousands of small frames do not spin
// against the other tests of a parallel ctest run (with two threads each it took ten times as
// long on a loaded machine).
#ifdef _OPENMP
const int kOneThread = (omp_set_num_threads(1), 1);
#endif

constexpr int kFrames = 10000;
constexpr double kRadius_m = 30.0;  // the course: a circle of 188 m
constexpr double kStep_m = 0.4;     // between frames

std::size_t peakResidentBytes() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stoul(line.substr(6)) * 1024;
  }
  return 0;
}

// Frame k: the robot on the circle, 120 ground points up to 2.5 m ahead of it (a rock every
// so often), seeded by k so that every build sees the same frame.
Frame frameAt(int k, Eigen::Vector3d& sensor) {
  const double a = k * kStep_m / kRadius_m;
  const double x = kRadius_m * std::cos(a), y = kRadius_m * std::sin(a), heading = a + M_PI / 2;
  sensor = {x, y, 0.5};
  std::mt19937 rng(static_cast<unsigned>(k));
  std::uniform_real_distribution<double> ahead(0.5, 2.5), side(-1.0, 1.0), unit(0.0, 1.0);
  Frame f;
  for (int i = 0; i < 120; ++i) {
    const double u = ahead(rng), v = side(rng);
    const double px = x + u * std::cos(heading) - v * std::sin(heading);
    const double py = y + u * std::sin(heading) + v * std::cos(heading);
    // Rocks at fixed places of the course: the same cells every lap.
    const bool rock = std::fmod(std::atan2(py, px) + M_PI, 0.2) < 0.01;
    f.add(static_cast<float>(px), static_cast<float>(py), rock ? 0.2f : 0.02f,
          rock ? core::Label::NonTraversable : core::Label::Traversable, rock ? 0.8f : 0.99f, 0.f,
          static_cast<float>(unit(rng)));
  }
  return f;
}

OctreeParams boxParams() {
  OctreeParams p;
  p.resolution_m = 0.1;
  p.extent_m = 12.0;  // the sensor stays within 3 m of the centre, the points within 2.7 m of it
  p.height_m = 4.0;
  p.center_z_m = 0.5;
  p.tile_voxels = 64;
  return p;
}

// Floats as bits: NaN (no evidence) equals NaN.
using Leaves = std::map<std::tuple<int, int, int, unsigned>,
                        std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t, int>>;

std::uint32_t bits(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

Leaves leaves(const TraversabilityOcTree& t) {
  Leaves out;
  for (auto it = t.begin_leafs(), end = t.end_leafs(); it != end; ++it) {
    const auto k = it.getKey();
    out[{k[0], k[1], k[2], it.getDepth()}] = {
        bits(it->getLogOdds()), bits(it->getTraversabilityLogOdds()), bits(it->getZetaMin()),
        bits(it->getCostMean()), it->getObservations()};
  }
  return out;
}

void insertFrames(TraversabilityOcTree& tree, int from, int to) {
  const OctreeParams p = boxParams();
  for (int k = from; k < to; ++k) {
    Eigen::Vector3d sensor;
    const Frame f = frameAt(k, sensor);
    upd::maps::insertScan(tree, f.view(), sensor, p, FusionParams{});
  }
}

}  // namespace

TEST(Soak, MemoryIsFlatOnceTheCourseIsMapped) {
  GridParams gp;
  gp.cell_size_m = 0.1;
  gp.extent_m = 20.0;
  TraversabilityGrid grid(gp);
  TraversabilityOcTree tree(boxParams());
  const int lap = static_cast<int>(2 * M_PI * kRadius_m / kStep_m);
  std::size_t grid_bytes = 0, grid_tiles = 0, tree_bytes = 0, tree_tiles = 0, hwm = 0;
  for (int k = 0; k < kFrames; ++k) {
    Eigen::Vector3d sensor;
    const Frame f = frameAt(k, sensor);
    upd::maps::integrateScan(grid, f.view(), sensor.head<2>(), k, FusionParams{});
    upd::maps::insertScan(tree, f.view(), sensor, boxParams(), FusionParams{});
    if (k == 2 * lap) {  // the course has been seen twice: the working set is reached
      grid_bytes = grid.memoryBytes(), grid_tiles = grid.storedTiles();
      tree_bytes = tree.memoryUsage() + tree.keptTileBytes(), tree_tiles = tree.keptTiles();
      hwm = peakResidentBytes();
    }
  }
  const std::size_t grid_end = grid.memoryBytes(), tree_end = tree.memoryUsage() + tree.keptTileBytes();
  std::printf("after 2 laps: grid %zu B (%zu tiles), tree %zu B (%zu tiles), VmHWM %zu B\n"
              "after %d frames (%.1f laps): grid %zu B (%zu tiles), tree %zu B (%zu tiles), "
              "VmHWM %zu B\n",
              grid_bytes, grid_tiles, tree_bytes, tree_tiles, hwm, kFrames, double(kFrames) / lap,
              grid_end, grid.storedTiles(), tree_end, tree.keptTiles(), peakResidentBytes());
  EXPECT_LE(grid.storedTiles(), grid_tiles + 2);  // which tiles lie wholly inside the window varies
  EXPECT_LE(grid_end, grid_bytes + grid_bytes / 20);  // within 5 %: the same cells, new values
  EXPECT_LE(tree.keptTiles(), tree_tiles + 1);
  EXPECT_LE(tree_end, tree_bytes + tree_bytes / 5);
#if defined(UPD_TEST_UNDER_ASAN)
  // AddressSanitizer holds freed blocks in its quarantine (up to 256 MB) before reusing them and
  // pads every block: the process's peak then measures the sanitizer's allocator (it grew by
  // 9.8 MB of 470 MB here), not the maps, whose own bytes are checked above.
#else
  EXPECT_LE(peakResidentBytes(), hwm + (8u << 20));  // no growth beyond 8 MB of allocator slack
#endif
}

TEST(Soak, TreeBuiltInTwoHalvesWithASaveAndReloadEqualsOneBuiltInOneGo) {
  constexpr int kHalf = 1200, kAll = 2400;  // 2,400 frames: 5 laps  // 5,000 frames: 10 laps
  TraversabilityOcTree one_go(boxParams());
  insertFrames(one_go, 0, kAll);
  one_go.mergeKeptTiles();

  const upd::test::TempDir tmp("soak");
  const std::string path = (tmp.path() / "half.ot").string();
  {
    TraversabilityOcTree first(boxParams());
    insertFrames(first, 0, kHalf);
    first.mergeKeptTiles();  // the whole first half, as `upd playback` writes it
    upd::maps::writeTraversabilityOt(first, path);
  }
  const auto second = upd::maps::readTraversabilityOt(path);
  insertFrames(*second, kHalf, kAll);
  second->mergeKeptTiles();
  const Leaves want = leaves(one_go);
  EXPECT_GT(want.size(), 50000u);
  EXPECT_TRUE(leaves(*second) == want);
}

TEST(Soak, GridBuiltInTwoHalvesWithASaveAndReloadEqualsOneBuiltInOneGo) {
  constexpr int kHalf = 2500, kAll = 5000;  // 5,000 frames: 10 laps
  GridParams gp;
  gp.cell_size_m = 0.1;
  gp.extent_m = 20.0;
  gp.extent_y_m = 16.0;
  gp.tile_cells = 48;
  const auto feed = [](TraversabilityGrid& g, int from, int to) {
    for (int k = from; k < to; ++k) {
      Eigen::Vector3d sensor;
      const Frame f = frameAt(k, sensor);
      upd::maps::integrateScan(g, f.view(), sensor.head<2>(), k, FusionParams{});
    }
  };
  TraversabilityGrid one_go(gp);
  feed(one_go, 0, kAll);

  const upd::test::TempDir tmp("soak-grid");
  const std::string path = (tmp.path() / "half.grid").string();
  {
    TraversabilityGrid first(gp);
    feed(first, 0, kHalf);
    upd::maps::writeGridState(first, path);
  }
  TraversabilityGrid second = upd::maps::readGridState(path);
  feed(second, kHalf, kAll);

  const TraversabilityGrid a = one_go.wholeRun(), b = second.wholeRun();
  ASSERT_EQ(a.originI(), b.originI());
  ASSERT_EQ(a.originJ(), b.originJ());
  ASSERT_EQ(a.sizeX(), b.sizeX());
  ASSERT_EQ(a.sizeY(), b.sizeY());
  std::size_t observed = 0;
  for (int cy = 0; cy < a.sizeY(); ++cy) {
    for (int cx = 0; cx < a.sizeX(); ++cx) {
      const upd::maps::GridCell &p = a.at(cx, cy), &q = b.at(cx, cy);
      observed += p.observed();
      ASSERT_EQ(std::memcmp(&p.logodds_nontrav, &q.logodds_nontrav, 7 * sizeof(float)), 0);
      ASSERT_EQ(p.hits, q.hits);
      ASSERT_EQ(p.zeta_count, q.zeta_count);
      ASSERT_EQ(p.cost_count, q.cost_count);
      ASSERT_EQ(std::memcmp(&p.last_seen_s, &q.last_seen_s, sizeof p.last_seen_s), 0);
    }
  }
  EXPECT_GT(observed, 30000u);
}

TEST(Soak, GridStateFileErrorsNameTheFile) {
  const upd::test::TempDir tmp("soak-bad");
  const std::string path = (tmp.path() / "bad.grid").string();
  std::ofstream(path) << "UPD grid state 1\ncell_size_m 0.1\n";
  try {
    upd::maps::readGridState(path);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("bad.grid"), std::string::npos) << e.what();
  }
  EXPECT_THROW(upd::maps::readGridState((tmp.path() / "none.grid").string()), std::runtime_error);
}
