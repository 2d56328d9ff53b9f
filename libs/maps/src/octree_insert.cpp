// Inserting a frame of scored points into the traversability tree: OctoMap's ray casting for
// occupancy plus one traversability update per voxel per frame (traversability_octree.h).
#include "upd/maps/traversability_octree.h"

#include <octomap/Pointcloud.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace upd::maps {

namespace {

struct FrameVoxel {
  std::uint32_t n_nontrav = 0, n_trav = 0;
  float zeta_min = std::numeric_limits<float>::quiet_NaN();
  double cost_sum = 0;
  std::uint32_t n_cost = 0;

  void add(const FrameVoxel& o) {
    n_nontrav += o.n_nontrav;
    n_trav += o.n_trav;
    zeta_min = std::fmin(zeta_min, o.zeta_min);  // NaN (none yet) gives the other
    cost_sum += o.cost_sum;
    n_cost += o.n_cost;
  }
};

// Key of a coordinate, clamped to the tree's key range (box corners may lie beyond it). OctoMap's
// occupancy trees have 16 levels: keys 0..65535, the world origin at key 32768 (tree_max_val).
octomap::OcTreeKey clampedKey(const TraversabilityOcTree& tree, const octomap::point3d& p) {
  constexpr double kTreeMaxVal = 32768.0;
  octomap::OcTreeKey k;
  for (int a = 0; a < 3; ++a) {
    const double v = std::floor(p(a) / tree.getResolution()) + kTreeMaxVal;
    k[a] = static_cast<octomap::key_type>(std::clamp(v, 0.0, 2.0 * kTreeMaxVal - 1.0));
  }
  return k;
}

// Sets (and crops to) the update box; returns true when it moved.
bool updateBox(TraversabilityOcTree& tree, const Eigen::Vector3d& sensor,
               const OctreeParams& params) {
  const Eigen::Vector3d size(params.extent_m, params.extent_m, params.height_m);
  const Eigen::Vector3d initial(params.center_x_m, params.center_y_m, params.center_z_m);
  Eigen::Vector3d center = initial;
  if (tree.bbxSet()) {
    const octomap::point3d c = tree.getBBXCenter();
    center = Eigen::Vector3d(c.x(), c.y(), c.z());
  }
  bool recenter = false;
  if (params.follow_robot) {
    const Eigen::Vector3d off = (sensor - center).cwiseAbs();
    recenter = (off.array() > params.recenter_fraction * size.array()).any();
  } else {
    // The box is kept in float: only a change of more than half a voxel is a new box.
    recenter = tree.bbxSet() &&
               (center - initial).cwiseAbs().maxCoeff() > 0.5 * tree.getResolution();
    center = initial;
  }
  if (tree.bbxSet() && !recenter) return false;
  if (recenter && params.follow_robot) {
    // Snapped to the voxel grid: the box does not jitter with the sensor.
    const double r = tree.getResolution();
    center = ((sensor / r).array().floor() + 0.5).matrix() * r;
  }
  octomap::point3d bmin(static_cast<float>(center.x() - 0.5 * size.x()),
                        static_cast<float>(center.y() - 0.5 * size.y()),
                        static_cast<float>(center.z() - 0.5 * size.z()));
  octomap::point3d bmax(static_cast<float>(center.x() + 0.5 * size.x()),
                        static_cast<float>(center.y() + 0.5 * size.y()),
                        static_cast<float>(center.z() + 0.5 * size.z()));
  tree.setBBXMin(bmin);
  tree.setBBXMax(bmax);
  tree.useBBXLimit(true);
  const octomap::OcTreeKey kmin = clampedKey(tree, bmin), kmax = clampedKey(tree, bmax);
  if (params.keep_outside_box) {
    // What was kept of the new box comes back first; then what lies outside it is kept.
    tree.restoreKeptTiles(kmin, kmax);
    tree.cropToKeyBoxKeeping(kmin, kmax, params.tile_voxels);
  } else {
    tree.cropToKeyBox(kmin, kmax);
  }
  return true;
}

// Whether a ray ending at `end` marks its end voxel hit: within range and inside the box, as
// OctoMap's computeUpdate tests.
struct HitTest {
  const TraversabilityOcTree& tree;
  octomap::point3d origin;
  double max_range;  // <= 0: none
  bool operator()(const octomap::point3d& end) const {
    return !(max_range > 0 && (end - origin).norm() > max_range) &&
           !(tree.bbxSet() && !tree.inBBX(end));
  }
};

// One fixed chunk of points, scanned on its own (the result does not depend on the threads).
struct Chunk {
  std::vector<octomap::point3d> ray_ends;  // points, or the centres of new voxels
  std::vector<octomap::OcTreeKey> voxels;  // discretize: each change of voxel, in order
  std::vector<std::pair<octomap::OcTreeKey, FrameVoxel>> runs;
  std::size_t inserted = 0, invalid = 0, unknown = 0;
};
constexpr std::size_t kChunk = 16384;

// Adds labelled point i to the run of its voxel.
inline void addToRun(FrameVoxel& run, const PointsWorld& points, std::size_t i, core::Label label) {
  if (label == core::Label::NonTraversable) {
    ++run.n_nontrav;
  } else {
    ++run.n_trav;
  }
  if (points.zeta != nullptr && std::isfinite(points.zeta[i])) {
    run.zeta_min = std::fmin(run.zeta_min, points.zeta[i]);
  }
  if (points.cost != nullptr && std::isfinite(points.cost[i])) {
    run.cost_sum += points.cost[i];
    ++run.n_cost;
  }
}

// Step 1 of insertScan for the points [begin, end): each point's voxel key, the changes of
// voxel, and the labelled points of each run in one voxel summed (with discretize, a voxel
// marks hit when its centre is within range and inside the box).
void scanChunk(const TraversabilityOcTree& tree, const PointsWorld& points,
               const OctreeParams& params, const HitTest& marksHit, std::size_t begin,
               std::size_t end, Chunk& ch) {
  octomap::OcTreeKey last_key;  // a default key is a real voxel: hence have_last
  bool have_last = false, last_hit = false;
  FrameVoxel run;
  const auto flush = [&] {
    if (run.n_nontrav + run.n_trav > 0) ch.runs.emplace_back(last_key, run);
    run = FrameVoxel{};
  };
  for (std::size_t i = begin; i < end; ++i) {
    const float x = points.x[i], y = points.y[i], z = points.z[i];
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      ++ch.invalid;
      continue;
    }
    ++ch.inserted;
    const octomap::point3d p(x, y, z);
    octomap::OcTreeKey key;
    const bool in_tree = tree.coordToKeyChecked(p, key);
    if (!params.discretize) ch.ray_ends.push_back(p);
    if (in_tree && !(have_last && key == last_key)) {
      flush();
      last_key = key;
      have_last = true;
      if (params.discretize) {
        ch.voxels.push_back(key);
        last_hit = marksHit(tree.keyToCoord(key));
      }
    }
    const core::Label label = points.label[i];
    if (label != core::Label::Traversable && label != core::Label::NonTraversable) {
      ++ch.unknown;
      continue;
    }
    if (!in_tree || !(params.discretize ? last_hit : marksHit(p))) continue;
    addToRun(run, points, i, label);
  }
  flush();
}

using FrameVoxels = std::unordered_map<octomap::OcTreeKey, FrameVoxel, octomap::OcTreeKey::KeyHash>;

// Step 2: the chunks in order: the rays (one per distinct end voxel with discretize) and the
// per-voxel sums of the frame.
void mergeChunks(const TraversabilityOcTree& tree, const std::vector<Chunk>& chunks,
                 bool discretize, octomap::Pointcloud& cloud, FrameVoxels& frame,
                 OctreeInsertStats& stats) {
  octomap::KeySet ends;
  std::size_t n_ends = 0;
  for (const Chunk& ch : chunks) n_ends += discretize ? ch.voxels.size() : ch.ray_ends.size();
  cloud.reserve(n_ends);
  for (const Chunk& ch : chunks) {
    stats.points_inserted += ch.inserted;
    stats.points_invalid += ch.invalid;
    stats.points_unknown += ch.unknown;
    for (const octomap::point3d& p : ch.ray_ends) cloud.push_back(p);
    for (const octomap::OcTreeKey& key : ch.voxels) {
      if (ends.insert(key).second) cloud.push_back(tree.keyToCoord(key));
    }
    for (const auto& [key, run] : ch.runs) frame[key].add(run);
  }
}

void checkInsertArgs(const TraversabilityOcTree& tree, const PointsWorld& points,
                     const Eigen::Vector3d& sensor_origin_world, const OctreeParams& params,
                     const FusionParams& fusion) {
  params.validate();
  fusion.validate();
  points.validate();
  core::requireParam(std::abs(tree.getResolution() - params.resolution_m) <= 1e-9 * params.resolution_m,
               "insertScan", "OctreeParams.resolution_m", params.resolution_m,
               "differs from the tree's resolution");
  core::requireParam(sensor_origin_world.allFinite(), "insertScan", "sensor_origin_world",
               std::to_string(sensor_origin_world.x()) + "," +
                   std::to_string(sensor_origin_world.y()) + "," +
                   std::to_string(sensor_origin_world.z()),
               "must be finite");
}

}  // namespace

OctreeInsertStats insertScan(TraversabilityOcTree& tree, const PointsWorld& points,
                             const Eigen::Vector3d& sensor_origin_world, const OctreeParams& params,
                             const FusionParams& fusion) {
  checkInsertArgs(tree, points, sensor_origin_world, params, fusion);
  OctreeInsertStats stats;
  stats.window_moved = updateBox(tree, sensor_origin_world, params);

  const octomap::point3d origin(static_cast<float>(sensor_origin_world.x()),
                                static_cast<float>(sensor_origin_world.y()),
                                static_cast<float>(sensor_origin_world.z()));
  const double max_range = params.max_range_m > 0 ? params.max_range_m : -1.0;
  // The rays: one per point, or (discretize) one per end voxel from its centre, as OctoMap's
  // computeDiscreteUpdate makes them. Consecutive points (image rows) mostly end in the same
  // voxel: what depends only on the voxel is worked out once per change of voxel.
  // 1. In fixed chunks of points, in parallel (the result does not depend on the thread count).
  const HitTest marks_hit{tree, origin, max_range};
  std::vector<Chunk> chunks((points.size + kChunk - 1) / kChunk);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(chunks.size()); ++cc) {
    const std::size_t begin = static_cast<std::size_t>(cc) * kChunk;
    scanChunk(tree, points, params, marks_hit, begin, std::min(points.size, begin + kChunk),
              chunks[static_cast<std::size_t>(cc)]);
  }
  // 2. The rays and the frame's per-voxel sums, chunk by chunk in order.
  octomap::Pointcloud cloud;
  FrameVoxels frame;
  mergeChunks(tree, chunks, params.discretize, cloud, frame, stats);

  tree.insertPointCloud(cloud, origin, max_range, /*lazy_eval=*/true);
  for (const auto& [key, v] : frame) {
    const float cost = v.n_cost > 0 ? static_cast<float>(v.cost_sum / v.n_cost)
                                    : std::numeric_limits<float>::quiet_NaN();
    if (tree.integrateTraversability(key, v.n_nontrav, v.n_trav, v.zeta_min, cost, fusion)) {
      ++stats.voxels_traversability;
    }
  }
  tree.updateInnerOccupancy();
  return stats;
}

}  // namespace upd::maps
