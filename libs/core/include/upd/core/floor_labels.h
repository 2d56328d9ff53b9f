// A geometric ground truth for real frames that carry no labels: the floor plane (found by
// RANSAC, floor_plane.h) is traversable, everything off it is not, and so is the floor's
// border with what stands on it or falls away from it.
//
// The rule, per finite point p with signed height h = n . p + d over the plane:
//  - |h| > off_floor_m: NonTraversable (an obstacle, a wall, a hole, a table top);
//  - else NonTraversable when an off-floor point lies within border_m of p (3D distance):
//    the floor at the foot of an obstacle, which a robot cannot stand on;
//  - else Traversable.
// Non-finite points are Unknown. off_floor_m bounds the unevenness a robot drives over (the
// 5 cm step of the generated scenes' truth, sim::TruthParams) and must exceed the sensor noise
// on the floor; border_m is the band the generated scenes' truth also marks (0.05 m) widened to
// the noise of a real depth camera.
#pragma once

#include "upd/core/floor_plane.h"
#include "upd/core/params.h"
#include "upd/core/point_cloud.h"

#include <vector>

namespace upd::core {

/// The rule of the header comment (`upd evaluate` uses the defaults).
struct GeometricLabelParams {
  double off_floor_m = 0.05;  ///< farther from the floor plane: non-traversable [m]
  double border_m = 0.10;     ///< floor points this close to an off-floor point: non-traversable

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("off_floor_m", off_floor_m, "points farther than this from the floor plane are obstacles [m]");
    v("border_m", border_m, "floor points this close to an obstacle point are obstacles too [m]");
  }
};

/// The labels of cloud by the rule above; plane (found) is in cloud's frame.
std::vector<Label> labelByFloor(const PointCloud& cloud, const FloorPlane& plane,
                                const GeometricLabelParams& params);

}  // namespace upd::core
