// The Unevenness Point Descriptor (paper eqs. 6-8).
//
// For every point, r = sum of the unit normals n_i of its neighbours within d_m (eq. 6), and
// zeta = |r| / k where k is the number of neighbours with a valid normal (eq. 8). zeta = 1 on any
// plane whatever its slope; it falls towards sqrt(2)/2 where normals meet at right angles. The
// direction of r gives the local slope. Both sums include the point itself.
#pragma once

#include "upd/core/kdtree.h"
#include "upd/core/normals.h"
#include "upd/core/params.h"

#include <cstdint>
#include <limits>
#include <vector>

namespace upd::core {

/// How runPipeline computes normals and the UPD (UpdParams::method). See pipeline.h for the
/// rule that picks the fast path and fast_upd.h for how far it is from the exact one.
enum class UpdMethod : int {
  Auto = 0,   ///< Fast when its preconditions hold (radius neighbourhoods), else Exact
  Exact = 1,  ///< k-d tree sums over the true neighbourhoods: equal to brute force
  Fast = 2,   ///< cost per point independent of d_m: window-scan normals, voxel-moment lattice UPD
};
/// The ini names of UpdMethod ([UpdParams] method); the loader also takes the numbers.
inline constexpr EnumName<UpdMethod> kUpdMethodNames[] = {
    {"auto", UpdMethod::Auto}, {"exact", UpdMethod::Exact}, {"fast", UpdMethod::Fast}};

struct UpdParams {
  double radius_m = 0.5;  ///< d_m, the UPD search radius [m] (eq. 1); follows the robot's size
  int knn = 0;            ///< > 0: sum over the knn nearest points instead (sparse data)
  int min_neighbors = 3;  ///< fewer neighbours with valid normals: the point is not scored
  UpdMethod method = UpdMethod::Auto;  ///< the normals and UPD path (pipeline.h)
  /// Fast path: lattice cells per d_m (fast_upd.h). The node work grows as its 4th power; the
  /// error falls with it (4: mean |delta zeta| ~2e-3; 8: ~7e-4 on the generated scenes).
  int fast_cells_per_radius = 4;
  /// Fast path: where the points are dense (a full-resolution frame), a finer lattice, up to
  /// twice fast_cells_per_radius, while its occupied cells number at most this many per point
  /// with a valid normal: the node work then stays a fixed share of the per-point work, and a
  /// voxelized or sparse cloud keeps fast_cells_per_radius (fast_upd.h). 0 turns this off.
  double fast_cells_per_point = 0.015;
  /// Fast path: a cell whose lattice nodes' zeta spread by more than this is not interpolated;
  /// its points get the lattice sums at their own position (fast_upd.h). 0 turns this off.
  double fast_refine_spread = 0.0;
  /// Fast path: points whose zeta lies within this of the classifier's zeta_min are summed
  /// exactly over their neighbourhood (fast_upd.h), so their label is the exact path's.
  /// 0 turns this off.
  double fast_exact_band = 0.0;

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("radius_m", radius_m, "UPD search radius d_m [m] (eq. 1): 0.5 small rover, 1.0 tractor");
    v("knn", knn, "if > 0, sum over the k nearest points instead of the radius");
    v("min_neighbors", min_neighbors, "points with fewer valid-normal neighbours get NaN");
    v.choice("method", method, kUpdMethodNames,
             "auto (fast unless knn > 0), exact (k-d tree, brute-force equal), fast (cost per "
             "point independent of d_m: image-window normals on organized clouds, a "
             "voxel-moment lattice for the UPD); the numbers 0, 1, 2 are also accepted");
    v("fast_cells_per_radius", fast_cells_per_radius,
      "fast path: lattice cells per d_m (2 .. 16); more is slower and closer to exact");
    v("fast_cells_per_point", fast_cells_per_point,
      "fast path: dense clouds get a finer lattice (up to 2 x fast_cells_per_radius) while its "
      "occupied cells number at most this many per point (0 = never)");
    v("fast_refine_spread", fast_refine_spread,
      "fast path: cells whose nodes' zeta spread by more than this are summed per point, "
      "not interpolated (0 = never)");
    v("fast_exact_band", fast_exact_band,
      "fast path: points whose zeta lies within this of [ClassifyParams] zeta_min are summed "
      "exactly over their neighbourhood, so their label is the exact path's (0 = never)");
  }
};

/// Per-point descriptor (r_x, r_y, r_z, zeta) and neighbour count k; NaN where not scored.
struct UpdResult {
  std::vector<float> rx, ry, rz, zeta;
  std::vector<std::uint32_t> k;  ///< neighbours with a valid normal (0 when not scored)
  std::size_t invalid = 0;       ///< points with NaN zeta

  std::size_t size() const { return zeta.size(); }
  bool isValid(std::size_t i) const { return zeta[i] == zeta[i]; }
  Eigen::Vector3f r(std::size_t i) const { return {rx[i], ry[i], rz[i]}; }

  /// n points, none scored yet (NaN, k = 0): where the exact and fast paths start.
  static UpdResult unscored(std::size_t n) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    UpdResult out;
    out.rx.assign(n, nan);
    out.ry.assign(n, nan);
    out.rz.assign(n, nan);
    out.zeta.assign(n, nan);
    out.k.assign(n, 0);
    return out;
  }
};

/// UPD of every point of cloud from its normals (exact: sums over the true neighbourhood).
UpdResult computeUpd(const PointCloud& cloud, const KdTree& tree, const Normals& normals,
                     const UpdParams& params);

}  // namespace upd::core
