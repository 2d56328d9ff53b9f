// Private to the pre-processing sources: the range/box test, the voxel grid in one pass (with
// the cut-off fused into it) and the compaction of a cloud by a keep mask.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "upd/core/point_cloud.h"
#include "upd/core/preprocess.h"

namespace upd::core::detail {

/// The test of cropRange for a finite point q: within the range of the sensor origin and inside
/// the box, each when enabled.
class RangeBoxTest {
 public:
  RangeBoxTest(const PreprocessParams& p, const Eigen::Vector3f& sensor_origin)
      : p_(p),
        origin_(sensor_origin),
        rmin2_(p.range_min_m * p.range_min_m),
        rmax2_(p.range_max_m * p.range_max_m) {}
  bool enabled() const { return p_.range_enabled || p_.box_enabled; }
  bool keeps(const Eigen::Vector3f& q) const {
    if (p_.range_enabled) {
      const double d2 = (q - origin_).cast<double>().squaredNorm();
      if (!(d2 >= rmin2_ && d2 <= rmax2_)) return false;
    }
    return !p_.box_enabled ||
           ((q.array() >= p_.box_min_m.array()).all() && (q.array() <= p_.box_max_m.array()).all());
  }

 private:
  const PreprocessParams& p_;
  Eigen::Vector3f origin_;
  double rmin2_, rmax2_;
};

/// The voxel grid of the finite points of in that test keeps (every finite point when test is
/// null) into out (unorganized; its buffers reused): one centroid per voxel, in order of first
/// appearance, colour averaged. Returns the number of points that passed.
std::size_t voxelize(const PointCloud& in, double voxel_m, const RangeBoxTest* test,
                     PointCloud& out);

/// Keeps the points of c where keep[i], in order, in place (an unorganized cloud).
void compactInPlace(PointCloud& c, const std::vector<char>& keep);

}  // namespace upd::core::detail
