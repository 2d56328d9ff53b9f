// Traversability from the UPD: a label and a cost in [0, 1] per point (paper section 5).
//
// Roughness comes from zeta, slope from the direction of r (the angle between r and up): all
// four components of the descriptor are used. A point is
//  - Unknown (cost NaN) when it has no UPD or fewer than min_neighbors neighbours;
//  - NonTraversable (cost 1) when zeta < zeta_min or slope > max_slope;
//  - Traversable otherwise, with cost = max(zeta term, slope term), where the zeta term rises
//    linearly from 0 at zeta_caution to 1 at zeta_min and the slope term is (slope/max_slope)^2.
// A learned classifier replaces this rule when a config sets `[ClassifyParams] classifier = FILE`
// (point_labeler.h, docs/EVALUATION.md).
// A point is "flagged" when its cost is > 0 because of zeta (zeta < zeta_caution): a gentle
// concave border such as the foot of a 20 deg ramp is flagged but stays traversable.
#pragma once

#include "upd/core/params.h"
#include "upd/core/point_cloud.h"
#include "upd/core/upd.h"

#include <vector>

namespace upd::core {

struct ClassifyParams {
  double zeta_min = 0.95;      ///< zeta below this: non-traversable [-]
  double zeta_caution = 0.99;  ///< zeta below this: cost starts to rise [-]
  double max_slope_rad = 25.0 * kDegToRad;  ///< slope of r above this: non-traversable [rad]
  int min_neighbors = 10;      ///< fewer UPD neighbours: unknown

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("zeta_min", zeta_min, "zeta below this is non-traversable (sqrt(2)/2 .. 1)");
    v("zeta_caution", zeta_caution, "zeta below this raises the cost (zeta_min .. 1)");
    v.angleDeg("max_slope_deg", max_slope_rad, "slope of r above this is non-traversable [deg]");
    v("min_neighbors", min_neighbors, "points with fewer UPD neighbours are unknown");
  }
};

struct Classification {
  std::vector<Label> label;
  std::vector<float> cost;       ///< [0, 1]; NaN for unknown
  std::vector<float> slope_rad;  ///< angle between r and up; NaN for unknown
  std::size_t traversable = 0, non_traversable = 0, unknown = 0;
};

/// up must be unit length.
Classification classify(const UpdResult& upd, const Eigen::Vector3f& up,
                        const ClassifyParams& params);
/// The same into out, reusing its buffers (a frame loop allocates nothing after the first).
void classify(const UpdResult& upd, const Eigen::Vector3f& up, const ClassifyParams& params,
              Classification& out);

}  // namespace upd::core
