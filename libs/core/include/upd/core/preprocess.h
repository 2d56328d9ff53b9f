// Pre-processing before the UPD (paper section 3): range cut-off, voxel down-sampling and
// statistical outlier removal, each switchable.
//
// Order: non-finite points are dropped, then the range/box cut-off, then the voxel grid
// (centroid per voxel, colour averaged), then outlier removal. Outlier removal runs on the
// down-sampled cloud: there the density is uniform, so the mean distance to the k nearest
// neighbours compares like with like across ranges, and it costs far less.
#pragma once

#include "upd/core/params.h"
#include "upd/core/point_cloud.h"

#include <vector>

namespace upd::core {

struct PreprocessParams {
  bool range_enabled = false;
  double range_min_m = 0.0;   ///< points nearer to the sensor origin are removed [m]
  double range_max_m = 10.0;  ///< points farther from the sensor origin are removed [m]
  bool box_enabled = false;   ///< keep only points inside [box_min_m, box_max_m] (cloud frame)
  Eigen::Vector3f box_min_m = Eigen::Vector3f::Constant(-10.f);
  Eigen::Vector3f box_max_m = Eigen::Vector3f::Constant(10.f);
  bool voxel_enabled = true;
  double voxel_m = 0.02;  ///< voxel edge [m]
  bool outlier_enabled = true;
  int outlier_k = 16;              ///< neighbours for the mean distance
  double outlier_std_mul = 2.0;    ///< alpha: removed if mean distance > mu + alpha * sigma

  void validate() const;
  /// Turns every step off (`upd analyze --no-preprocess`).
  void disableAll() { range_enabled = box_enabled = voxel_enabled = outlier_enabled = false; }
  bool anyEnabled() const { return range_enabled || box_enabled || voxel_enabled || outlier_enabled; }
  template <class V>
  void visit(V& v) {
    v("range_enabled", range_enabled, "apply the range cut-off");
    v("range_min_m", range_min_m, "minimum distance from the sensor origin [m]");
    v("range_max_m", range_max_m, "maximum distance from the sensor origin [m]");
    v("box_enabled", box_enabled, "keep only points inside the box");
    v("box_min_m", box_min_m, "box minimum corner x,y,z [m]");
    v("box_max_m", box_max_m, "box maximum corner x,y,z [m]");
    v("voxel_enabled", voxel_enabled, "apply voxel down-sampling (centroid per voxel)");
    v("voxel_m", voxel_m, "voxel edge length [m]");
    v("outlier_enabled", outlier_enabled, "apply statistical outlier removal");
    v("outlier_k", outlier_k, "neighbours for the mean distance");
    v("outlier_std_mul", outlier_std_mul, "alpha: remove if mean distance > mu + alpha sigma");
  }
};

struct PreprocessStats {
  std::size_t points_in = 0;
  std::size_t non_finite = 0;
  std::size_t range_removed = 0;
  std::size_t after_voxel = 0;
  std::size_t outliers_removed = 0;
  std::size_t points_out = 0;
};

/// Each step alone (they keep the sensor origin; the output is never organized except for
/// cropRange on an organized input with keep_organized, which sets removed points to NaN).
PointCloud dropNonFinite(const PointCloud& in);
PointCloud cropRange(const PointCloud& in, const PreprocessParams& p);
PointCloud voxelDownsample(const PointCloud& in, double voxel_m);
PointCloud removeStatisticalOutliers(const PointCloud& in, int k, double std_mul);

/// What the outlier filter thresholds: every finite point's mean distance to its k nearest
/// other points (NaN for a point that is not finite or has no other point). The neighbours
/// come from a grid of cells sized for about (k + 1) / 2 points each (the block of cells around
/// a point's own, then the wider block, then a third ring, until the k-th distance is certain);
/// the few points whose neighbours lie beyond 3 rings are compared with every point (a k-d tree
/// answers when there are many). The exact k nearest: the k-d tree's answer up to float
/// rounding.
std::vector<double> meanNeighbourDistances(const PointCloud& in, int k);
/// The same into mean_dist (its buffer reused; the search's buffers are the calling thread's,
/// kept from call to call).
void meanNeighbourDistances(const PointCloud& in, int k, std::vector<double>& mean_dist);

/// The whole chain. With every step disabled the input is returned unchanged (organized, NaNs
/// kept), so invalid points are scored as NaN and counted instead of silently dropped.
PointCloud preprocess(const PointCloud& in, const PreprocessParams& p,
                      PreprocessStats* stats = nullptr);

/// The same into out, whose buffers are reused when no step or the cut-off alone is enabled
/// (the input is copied) and when the voxel grid is: then the cut-off and the voxel grid run
/// in one pass over the input and the outlier filter on the centroids in place. The output is
/// the steps' one after the other, bit for bit.
void preprocess(const PointCloud& in, const PreprocessParams& p, PointCloud& out,
                PreprocessStats* stats = nullptr);

}  // namespace upd::core
