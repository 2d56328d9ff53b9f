// Inserting a frame of scored points into the traversability tree: OctoMap's ray casting for
// occupancy plus one traversability update per voxel per frame (traversability_octree.h).
#include "upd/maps/traversability_octree.h"

#include <octomap/Pointcloud.h>

#include "keep_if.h"
#include "key_sets.h"
#include "upd/core/vector_clones.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace upd::maps {

namespace {

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

// Whether a ray ending at `end` is cast and marks its end voxel hit: within range and inside
// the box, as OctoMap's computeUpdate tests (the traversability of the voxel asks the same).
struct HitTest {
  const TraversabilityOcTree& tree;
  octomap::point3d origin;
  double max_range;  // <= 0: none
  bool operator()(const octomap::point3d& end) const {
    return !(max_range > 0 && (end - origin).norm() > max_range) &&
           !(tree.bbxSet() && !tree.inBBX(end));
  }
};

// A point's share of its run's sums: nothing unless on (a labelled point whose voxel marks
// hit); its zeta and cost only where finite (a run's zeta_min +inf while it has none).
struct PointShare {
  std::uint32_t nontrav, trav, has_cost;
  float zeta, cost;
  PointShare(const PointsWorld& points, std::size_t i, core::Label label, bool on) {
    nontrav = on & (label == core::Label::NonTraversable);
    trav = on & (label == core::Label::Traversable);
    const float z = points.zeta != nullptr ? points.zeta[i] : kNanF;
    const float c = points.cost != nullptr ? points.cost[i] : kNanF;
    zeta = on & std::isfinite(z) ? z : kInfF;
    has_cost = on & std::isfinite(c);
    cost = has_cost ? c : 0.f;
  }
  static constexpr float kNanF = std::numeric_limits<float>::quiet_NaN();
  static constexpr float kInfF = std::numeric_limits<float>::infinity();
};

// The labelled points' sums of a run of points in one voxel, or of a voxel over the frame (the
// runs' sums added). The scan keeps its runs' in registers, a point's share added without a
// branch (the labels and the NaN of unscored points are mixed in a frame) when it is in the run.
struct VoxelSums {
  std::uint32_t nontrav = 0, trav = 0, n_cost = 0;
  float zeta_min = PointShare::kInfF;  // (+inf: none)
  double cost_sum = 0;
  void add(const PointShare& p, bool in_run) {
    nontrav += in_run ? p.nontrav : 0;
    trav += in_run ? p.trav : 0;
    zeta_min = std::min(zeta_min, in_run ? p.zeta : PointShare::kInfF);
    cost_sum += in_run ? p.cost : 0.f;
    n_cost += in_run ? p.has_cost : 0;
  }
  void add(const VoxelSums& o) {
    nontrav += o.nontrav;
    trav += o.trav;
    zeta_min = std::min(zeta_min, o.zeta_min);
    cost_sum += o.cost_sum;
    n_cost += o.n_cost;
  }
};

// One fixed chunk of points, scanned on its own (the result does not depend on the threads).
struct Chunk {
  std::vector<octomap::point3d> ray_ends;  // points, or the centres of new voxels
  std::vector<octomap::OcTreeKey> voxels;  // discretize: each change of voxel, in order
  std::vector<std::pair<octomap::OcTreeKey, VoxelSums>> runs;
  std::size_t inserted = 0, invalid = 0, unknown = 0;
};
constexpr std::size_t kChunk = 16384;

// A point's voxel key packed in 48 bits (x | y << 16 | z << 32), or why it has none.
constexpr std::uint64_t kNotFinite = ~std::uint64_t{0}, kOutsideTree = kNotFinite - 1;
inline octomap::OcTreeKey unpack(std::uint64_t code) {
  return octomap::OcTreeKey(static_cast<octomap::key_type>(code & 0xFFFF),
                            static_cast<octomap::key_type>((code >> 16) & 0xFFFF),
                            static_cast<octomap::key_type>(code >> 32));
}

// The codes of points [0, n): OctoMap's coordToKeyChecked exactly (the key floor(v) + 32768
// of v = factor * coordinate in double, within [0, 65536)), without a call to floor per
// coordinate (the library's baseline x86-64 has no rounding instruction), so that the loop
// vectorizes.
UPD_VECTOR_CLONES
void keyCodes(const float* __restrict x, const float* __restrict y, const float* __restrict z,
              std::size_t n, double factor, std::uint64_t* __restrict code) {
  constexpr double kHalf = 32768.0;  // OctoMap's tree_max_val: 16 levels
  for (std::size_t i = 0; i < n; ++i) {
    const bool finite = (x[i] - x[i]) + (y[i] - y[i]) + (z[i] - z[i]) == 0.f;
    const double vx = factor * x[i], vy = factor * y[i], vz = factor * z[i];
    const bool inside = (vx >= -kHalf) & (vx < kHalf) & (vy >= -kHalf) & (vy < kHalf) &
                        (vz >= -kHalf) & (vz < kHalf);  // (NaN: false)
    // floor(v) as truncation, one less below a negative v's whole part (|v| < 2^15: exact);
    // v outside taken as 0 (a conversion of NaN or a huge v would be undefined).
    const double wx = detail::keepIf(inside, vx), wy = detail::keepIf(inside, vy),
                 wz = detail::keepIf(inside, vz);
    const auto tx = static_cast<std::int32_t>(wx), ty = static_cast<std::int32_t>(wy),
               tz = static_cast<std::int32_t>(wz);
    const std::int32_t fx = tx - (wx < static_cast<double>(tx)),
                       fy = ty - (wy < static_cast<double>(ty)),
                       fz = tz - (wz < static_cast<double>(tz));
    const std::uint64_t key = static_cast<std::uint64_t>(fx + 32768) |
                              static_cast<std::uint64_t>(fy + 32768) << 16 |
                              static_cast<std::uint64_t>(fz + 32768) << 32;
    // (Masks, not a select: no branch. kOutsideTree is kNotFinite - 1.)
    const std::uint64_t ok = 0 - static_cast<std::uint64_t>(finite & inside);
    code[i] = (key & ok) | ((kNotFinite - static_cast<std::uint64_t>(finite)) & ~ok);
  }
}

// Step 1 of insertScan for the points [begin, end): each point's voxel key, the voxels as
// they open, and the labelled points of each run in one voxel summed (without discretize, only
// the points that mark their voxel hit; with it, whether the voxel's centre does is asked
// once per voxel of the frame, after the merge). Two runs stay open, the last
// two voxels met: a surface on a voxel boundary (a floor at z = 0 in the world frame, its
// points' noise across it) alternates between two voxels from point to point, which one open
// run closed at every other point.
void scanChunk(const TraversabilityOcTree& tree, const PointsWorld& points,
               const OctreeParams& params, const HitTest& marksHit, std::size_t begin,
               std::size_t end, Chunk& ch) {
  // The two open runs, named rather than an array indexed by the one met last, which the
  // compiler would keep in memory (each point's sums a load and a store behind the last).
  std::uint64_t code0 = kOutsideTree, code1 = kOutsideTree;  // (none)
  VoxelSums run0, run1;
  bool last = false;  // the voxel met last: code1's
  const auto close = [&](std::uint64_t code, VoxelSums run) {
    if (run.nontrav + run.trav > 0) ch.runs.emplace_back(unpack(code), run);
  };
  constexpr std::size_t kBlock = 2048;
  std::uint64_t codes[kBlock];
  const double factor = 1.0 / tree.getResolution();  // (OctoMap's resolution_factor)
  for (std::size_t b = begin; b < end; b += kBlock) {
    const std::size_t n = std::min(kBlock, end - b);
    keyCodes(points.x + b, points.y + b, points.z + b, n, factor, codes);
    for (std::size_t j = 0; j < n; ++j) {
      const std::uint64_t code = codes[j];
      if (code == kNotFinite) {
        ++ch.invalid;
        continue;
      }
      const std::size_t i = b + j;
      ++ch.inserted;
      const auto point = [&] { return octomap::point3d(points.x[i], points.y[i], points.z[i]); };
      const bool in_tree = code != kOutsideTree;
      if (!params.discretize) ch.ray_ends.push_back(point());
      if (in_tree && code != (last ? code1 : code0)) {
        last = !last;  // (the other one: the voxel met before, or the one to close and reopen)
        if (code != (last ? code1 : code0)) {
          if (last) {
            close(code1, run1);
            code1 = code, run1 = VoxelSums{};
          } else {
            close(code0, run0);
            code0 = code, run0 = VoxelSums{};
          }
          if (params.discretize) ch.voxels.push_back(unpack(code));
        }
      }
      const core::Label label = points.label[i];
      const bool labelled =
          (label == core::Label::Traversable) | (label == core::Label::NonTraversable);
      ch.unknown += !labelled;
      if (!in_tree) continue;
      const PointShare share(points, i, label,
                             params.discretize ? labelled : labelled && marksHit(point()));
      run0.add(share, !last);
      run1.add(share, last);
    }
  }
  close(last ? code0 : code1, last ? run0 : run1);  // (the one met before last first)
  close(last ? code1 : code0, last ? run1 : run0);
}

// The frame's labelled points summed per voxel: voxels.keys()[i]'s sums in sums[i].
struct FrameVoxels {
  detail::FlatKeySet voxels;
  std::vector<VoxelSums> sums;
};

// Step 2: the chunks in order: the rays (one per distinct end voxel with discretize) and the
// per-voxel sums of the frame.
void mergeChunks(const TraversabilityOcTree& tree, const std::vector<Chunk>& chunks,
                 bool discretize, octomap::Pointcloud& cloud, FrameVoxels& frame,
                 OctreeInsertStats& stats) {
  std::size_t n_ends = 0, n_runs = 0;
  for (const Chunk& ch : chunks) {
    n_ends += discretize ? ch.voxels.size() : ch.ray_ends.size();
    n_runs += ch.runs.size();
  }
  cloud.reserve(n_ends);
  detail::FlatKeySet ends;
  ends.clear(discretize ? n_ends : 0);
  frame.voxels.clear(n_runs / 2);  // (most voxels hold several runs: it grows where not)
  for (const Chunk& ch : chunks) {
    stats.points_inserted += ch.inserted;
    stats.points_invalid += ch.invalid;
    stats.points_unknown += ch.unknown;
    for (const octomap::point3d& p : ch.ray_ends) cloud.push_back(p);
    for (const octomap::OcTreeKey& key : ch.voxels) {
      if (ends.insert(key).second) cloud.push_back(tree.keyToCoord(key));
    }
    for (const auto& [key, run] : ch.runs) {
      const auto [i, added] = frame.voxels.insert(key);
      if (added) frame.sums.emplace_back();
      frame.sums[i].add(run);
    }
  }
}

// The keys a ray of a chunk of ends marks: the free voxels along it (from its end back to the
// box's edge) and its end voxel, as OctoMap's computeUpdate finds them with an update box.
struct RayKeys {
  std::vector<octomap::OcTreeKey> free, occupied;
};

// OctoMap's insertPointCloud(ends, origin, max_range, lazy_eval = true) for a tree with an
// update box (updateBox sets one before): the same free and occupied voxels (a voxel both is
// occupied), each updated once, without OctoMap's set nodes and its critical sections around
// every insert; the rays cast in fixed chunks on the team, their keys gathered in chunk order.
// The voxels updated are appended to changed.
void updateOccupancy(TraversabilityOcTree& tree, const octomap::Pointcloud& ends,
                     const HitTest& marksHit, std::vector<octomap::OcTreeKey>& changed) {
  constexpr std::size_t kRays = 256;
  std::vector<RayKeys> chunks((ends.size() + kRays - 1) / kRays);
#pragma omp parallel
  {
    octomap::KeyRay ray;
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(chunks.size()); ++c) {
      RayKeys& out = chunks[static_cast<std::size_t>(c)];
      const std::size_t e = std::min(ends.size(), (static_cast<std::size_t>(c) + 1) * kRays);
      for (std::size_t i = static_cast<std::size_t>(c) * kRays; i < e; ++i) {
        const octomap::point3d& p = ends[i];
        if (!marksHit(p)) continue;
        octomap::OcTreeKey key;
        if (tree.coordToKeyChecked(p, key)) out.occupied.push_back(key);
        if (!tree.computeRayKeys(marksHit.origin, p, ray)) continue;
        for (auto k = ray.rbegin(); k != ray.rend() && tree.inBBX(*k); ++k) out.free.push_back(*k);
      }
    }
  }
  detail::VoxelMarks marks;  // (a few allocations a frame; thread_local costs a call a use)
  std::size_t n_keys = 0;
  for (const RayKeys& c : chunks) n_keys += c.free.size() + c.occupied.size();
  marks.clear(n_keys / 32);  // (most keys repeat, and a brick holds 64: it grows where not)
  for (const RayKeys& c : chunks) {
    for (const auto& k : c.occupied) marks.markOccupied(k);
  }
  for (const RayKeys& c : chunks) {
    for (const auto& k : c.free) marks.markFree(k);
  }
  tree.updateNodes(marks.free(), marks.occupied());
  changed.insert(changed.end(), marks.free().begin(), marks.free().end());
  changed.insert(changed.end(), marks.occupied().begin(), marks.occupied().end());
}

void checkInsertArgs(const TraversabilityOcTree& tree, const PointsWorld& points,
                     const Eigen::Vector3d& sensor_origin_world, const OctreeParams& params,
                     const FusionParams& fusion) {
  params.validate();
  fusion.validate();
  points.validate();
  core::requireParam(
      std::abs(tree.getResolution() - params.resolution_m) <= 1e-9 * params.resolution_m,
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

  // The voxels this frame changes, whose inner nodes are updated after (the rest of the tree
  // is up to date: updateBox's crop updated it whole).
  thread_local std::vector<octomap::OcTreeKey> changed;
  changed.clear();
  updateOccupancy(tree, cloud, marks_hit, changed);
  for (std::size_t i = 0; i < frame.sums.size(); ++i) {
    const octomap::OcTreeKey& key = frame.voxels.keys()[i];
    if (params.discretize && !marks_hit(tree.keyToCoord(key))) continue;
    const VoxelSums& v = frame.sums[i];
    const float cost = v.n_cost > 0 ? static_cast<float>(v.cost_sum / v.n_cost)
                                    : PointShare::kNanF;
    const float zeta_min = v.zeta_min < PointShare::kInfF ? v.zeta_min : PointShare::kNanF;
    if (tree.integrateTraversability(key, v.nontrav, v.trav, zeta_min, cost, fusion)) {
      ++stats.voxels_traversability;
      changed.push_back(key);
    }
  }
  tree.updateInnerOccupancy(changed);
  return stats;
}

}  // namespace upd::maps
