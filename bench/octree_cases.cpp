// The OctoMap update of `upd playback` against OctoMap's own insert, on the sensor-rate path's
// scored frames: upd::maps::insertScan (occupancy by OctoMap's ray-casting update, then the
// traversability of the end voxels, then the inner nodes above the changed voxels) against
// octomap::OcTree::insertPointCloud + updateInnerOccupancy (occupancy alone) with the same
// resolution, range and discretized rays, one core each, in the same run.
#include <omp.h>

#include <cstdio>
#include <memory>
#include <vector>

#include "cases.h"
#include "upd/core/stopwatch.h"

#ifdef UPD_BENCH_HAVE_MAPS
#include <octomap/OcTree.h>

#include "upd/maps/fusion.h"
#include "upd/maps/traversability_octree.h"
#endif

namespace core = upd::core;

namespace upd::bench {

#ifdef UPD_BENCH_HAVE_MAPS
namespace {

// config/dune-kinect-realtime.ini's and config/dune-kinect.ini's [OctreeParams].
maps::OctreeParams playbackOctree() {
  maps::OctreeParams p;
  p.resolution_m = 0.1;
  p.max_range_m = 5.0;
  return p;
}

// One frame in the world frame, scored by the sensor-rate path, as the octree stage gets it.
struct ScoredFrame {
  core::PipelineResult result;
  core::PointCloud world;
  Eigen::Vector3d origin;
  octomap::Pointcloud finite;  // the peer's input: every finite point (it takes no labels)
};

ScoredFrame scoreFrame(const Frame& fr) {
  ScoredFrame s;
  const core::PointCloud cloud = inputCloud(fr);
  core::runPipeline(cloud, sensorRateParams(fr.up), s.result);
  core::transformCloud(s.result.cloud, fr.pose_world_cloud.cast<double>(), s.world);
  s.origin = fr.pose_world_cloud.translation().cast<double>();
  for (std::size_t i = 0; i < s.world.size(); ++i) {
    if (std::isfinite(s.world.x[i]) && std::isfinite(s.world.y[i]) &&
        std::isfinite(s.world.z[i])) {
      s.finite.push_back(s.world.x[i], s.world.y[i], s.world.z[i]);
    }
  }
  return s;
}

// Occupied leaves of a tree at the finest depth.
template <class Tree>
std::size_t occupiedLeaves(const Tree& tree) {
  std::size_t n = 0;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (tree.isNodeOccupied(*it)) n += std::size_t{1} << (3 * (tree.getTreeDepth() - it.getDepth()));
  }
  return n;
}

// The medians of one insert into a tree that already holds `before` inserts of the frame (0: a
// new tree), ours on one core and two and OctoMap's, run by run in turn. The trees are built
// and filled outside the clocks.
struct OctreeTiming {
  double ours_one = kNaN, ours_two = kNaN, octomap = kNaN;
  std::size_t ours_occupied = 0, octomap_occupied = 0;
};

OctreeTiming timeInserts(const ScoredFrame& s, int before, int repeats) {
  const maps::OctreeParams p = playbackOctree();
  const maps::FusionParams fusion;
  const maps::PointsWorld view = maps::viewPoints(s.world, s.result.classes, &s.result.upd);
  std::vector<double> one, two, peer;
  OctreeTiming t;
  for (int run = -1; run < repeats; ++run) {
    for (int threads = 1; threads <= 2; ++threads) {
      omp_set_num_threads(threads);
      auto tree = std::make_unique<maps::TraversabilityOcTree>(p);
      for (int i = 0; i < before; ++i) maps::insertScan(*tree, view, s.origin, p, fusion);
      const core::Stopwatch w;
      maps::insertScan(*tree, view, s.origin, p, fusion);
      const double ms = w.elapsedMs();
      if (run >= 0) (threads == 1 ? one : two).push_back(ms);
      if (threads == 1) t.ours_occupied = occupiedLeaves(*tree);
    }
    omp_set_num_threads(1);
    auto tree = std::make_unique<octomap::OcTree>(p.resolution_m);
    const octomap::point3d origin(static_cast<float>(s.origin.x()),
                                  static_cast<float>(s.origin.y()),
                                  static_cast<float>(s.origin.z()));
    for (int i = 0; i < before; ++i) {
      tree->insertPointCloud(s.finite, origin, p.max_range_m, true, p.discretize);
      tree->updateInnerOccupancy();
    }
    const core::Stopwatch w;
    tree->insertPointCloud(s.finite, origin, p.max_range_m, true, p.discretize);
    tree->updateInnerOccupancy();
    const double ms = w.elapsedMs();
    if (run >= 0) peer.push_back(ms);
    t.octomap_occupied = occupiedLeaves(*tree);
  }
  t.ours_one = median(one), t.ours_two = median(two), t.octomap = median(peer);
  return t;
}

json octreeCase(const Frame& fr, const Options& o) {
  json c = {{"name", fr.name}, {"source", fr.source}};
  if (!fr.available) {
    c["skipped"] = fr.skip_reason;
    std::printf("%-30s skipped: %s\n", fr.name.c_str(), fr.skip_reason.c_str());
    return c;
  }
  const ScoredFrame s = scoreFrame(fr);
  c["points_inserted"] = s.finite.size();
  for (const int before : {0, 4}) {
    const OctreeTiming t = timeInserts(s, before, o.repeats);
    const char* key = before == 0 ? "new_tree" : "fifth_insert";
    c[key] = {{"ours_one_core_ms", num(t.ours_one)},
              {"ours_two_core_ms", num(t.ours_two)},
              {"octomap_ms", num(t.octomap)},
              {"ratio_ours_over_octomap", num(t.ours_one / t.octomap)},
              {"same_occupied_voxels", t.ours_occupied == t.octomap_occupied},
              {"occupied_voxels", t.ours_occupied}};
    std::printf("%-30s %-12s %7zu points  ours %6.2f ms (two cores %5.2f)  OctoMap %6.2f ms  "
                "ours/OctoMap %.2fx  occupied voxels %zu / %zu%s\n",
                before == 0 ? fr.name.c_str() : "", before == 0 ? "new tree" : "5th insert",
                s.finite.size(), t.ours_one, t.ours_two, t.octomap, t.ours_one / t.octomap,
                t.ours_occupied, t.octomap_occupied,
                t.ours_occupied == t.octomap_occupied ? "" : "  DIFFER");
  }
  std::fflush(stdout);
  return c;
}

}  // namespace
#endif

json octreeCases(const std::vector<Frame>& frames, const Options& o) {
  printTitle(
      "The OctoMap update of `upd playback` (0.1 m voxels, range 5 m, one ray per end voxel): "
      "upd::maps::insertScan (occupancy, traversability, inner nodes) against OctoMap's "
      "insertPointCloud + updateInnerOccupancy (occupancy alone), one core each, on the "
      "sensor-rate path's scored frames in the world frame");
#ifdef UPD_BENCH_HAVE_MAPS
  json cases = json::array();
  for (const Frame& fr : frames) cases.push_back(octreeCase(fr, o));
  return cases;
#else
  std::printf("skipped: libs/maps is not built\n");
  return {{"skipped", "libs/maps is not built"}};
#endif
}

}  // namespace upd::bench
