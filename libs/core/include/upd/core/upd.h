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
#include <vector>

namespace upd {

struct UpdParams {
  double radius_m = 0.5;  ///< d_m, the UPD search radius [m] (eq. 1); follows the robot's size
  int knn = 0;            ///< > 0: sum over the knn nearest points instead (sparse data)
  int min_neighbors = 3;  ///< fewer neighbours with valid normals: the point is not scored

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("radius_m", radius_m, "UPD search radius d_m [m] (eq. 1): 0.5 small rover, 1.0 tractor");
    v("knn", knn, "if > 0, sum over the k nearest points instead of the radius");
    v("min_neighbors", min_neighbors, "points with fewer valid-normal neighbours get NaN");
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
};

/// UPD of every point of cloud from its normals (exact: sums over the true neighbourhood).
UpdResult computeUpd(const PointCloud& cloud, const KdTree& tree, const Normals& normals,
                     const UpdParams& params);

}  // namespace upd
