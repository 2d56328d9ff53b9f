// Negative obstacles (a ditch, the edge of a platform seen from above) as missing ground.
//
// The UPD scores the points a camera sees; a ditch's near rim is flat ground (zeta = 1) and its
// floor next to that rim is hidden, so the UPD alone sees only the far wall and far rim. What
// betrays the ditch is the ground that is missing: walking up an image column (from the bottom,
// near, to the top, far), consecutive valid points normally step a few centimetres across the
// ground; at a rim they jump across the hidden part and land lower (on the far wall or the
// floor). A jump longer than min_gap_m whose far point lies more than min_drop_m below its near
// point is a gap in the ground: the segment between the two points (both ends included) is
// reported. Positive obstacles cast the same kind of shadow (a rock's crown, then the ground
// behind it), so the caller keeps only gaps whose near point stands on ground known to be
// traversable (NavigationLoop checks the fused map).
#pragma once

#include "upd/core/params.h"
#include "upd/core/point_cloud.h"

#include <Eigen/Core>

#include <vector>

namespace upd::nav {

/// Loaded from [NegativeObstacleParams].
struct NegativeObstacleParams {
  bool enabled = true;
  double min_gap_m = 0.2;    ///< horizontal jump between consecutive column points [m]
  double min_drop_m = 0.08;  ///< the far point is at least this much lower [m]
  double max_range_m = 5.0;  ///< near points farther than this from the sensor are ignored [m]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("enabled", enabled, "detect missing ground (ditches, drops) in the depth image");
    v("min_gap_m", min_gap_m, "horizontal jump across hidden ground that counts as a gap [m]");
    v("min_drop_m", min_drop_m, "the far side of a gap must be this much lower [m]");
    v("max_range_m", max_range_m, "gaps whose near point is farther than this are ignored [m]");
  }
};

/// One gap in the ground along an image column (world frame, z up).
struct GroundGap {
  Eigen::Vector3d near_world;  ///< last point before the hidden ground
  Eigen::Vector3d far_world;   ///< first point after it, lower
};

/// The gaps of an organized cloud in the world frame (z up, image rows top = far), with its
/// sensor origin set; ground_z_m is the height of the ground under the robot. An unorganized
/// cloud has no columns: no gaps.
std::vector<GroundGap> findGroundGaps(const core::PointCloud& organized_world, double ground_z_m,
                                      const NegativeObstacleParams& params);

/// Points every spacing_m (> 0) along the gap's horizontal segment, near and far ends included.
std::vector<Eigen::Vector2d> sampleGap(const GroundGap& gap, double spacing_m);

}  // namespace upd::nav
