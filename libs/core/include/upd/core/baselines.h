// The paper's baselines, for comparison with the UPD (section 5, Fig. 5).
//
// Roughness index: the standard deviation of elevation (the projection of the points on up)
// over the same neighbourhood as the UPD. It reads a smooth 20 deg ramp as rough, which the UPD
// does not. Inclination index: the angle between up and the normal of the plane fitted (PCA) to
// the same neighbourhood.
#pragma once

#include "upd/core/kdtree.h"
#include "upd/core/params.h"
#include "upd/core/point_cloud.h"

#include <vector>

namespace upd::core {

struct BaselineParams {
  double radius_m = 0.5;          ///< neighbourhood radius, the same d_m as the UPD [m]
  double roughness_max_m = 0.05;  ///< roughness index above this: non-traversable [m]
  double max_inclination_rad = 25.0 * kDegToRad;  ///< inclination above this: non-traversable
  int min_neighbors = 10;         ///< fewer neighbours: unknown

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("radius_m", radius_m, "neighbourhood radius [m], the same d_m as the UPD");
    v("roughness_max_m", roughness_max_m, "roughness index above this is non-traversable [m]");
    v.angleDeg("max_inclination_deg", max_inclination_rad,
               "inclination index above this is non-traversable [deg]");
    v("min_neighbors", min_neighbors, "points with fewer neighbours are unknown");
  }
};

struct BaselineResult {
  std::vector<float> roughness_m;      ///< std dev of elevation [m]; NaN if not scored
  std::vector<float> inclination_rad;  ///< [rad]; NaN if not scored
  std::vector<Label> roughness_label;  ///< the roughness-index classification
  std::size_t invalid = 0;
};

/// Both indices for every point of cloud. up must be unit length.
BaselineResult computeBaselines(const PointCloud& cloud, const KdTree& tree,
                                const Eigen::Vector3f& up, const BaselineParams& params);

}  // namespace upd::core
