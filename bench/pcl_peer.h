// The peer the benchmark compares with: the paper's pipeline as its authors built it on PCL
// (voxel grid, PCA normals by a k-d tree radius search, the UPD by a second radius search), and
// PCL's IntegralImageNormalEstimation for normals alone.
//
// PCL types stay in pcl_peer.cpp: this header speaks upd::PointCloud, so upd_bench.cpp does not
// compile PCL's templates. Every function runs on one thread (PCL's NormalEstimation is
// single-threaded; the OMP variant is not what the paper used) and converts its input to PCL's
// point type before the clock starts.
#pragma once

#include <Eigen/Core>

#include "upd/core/point_cloud.h"
#include "upd/core/upd.h"

namespace upd::bench {

struct PeerSettings {
  bool voxel_enabled = true;
  double voxel_m = 0.02;                          ///< pcl::VoxelGrid leaf size [m]
  double normal_radius_m = 0.05;                  ///< pcl::NormalEstimation radius [m]
  double upd_radius_m = 0.5;                      ///< d_m of the second radius search [m]
  int min_neighbors = 3;                          ///< as UpdParams::min_neighbors
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< for the orientation rule of normals.h
  double vertical_band_rad = 0.0;                 ///< as NormalParams::vertical_band_rad
  bool outlier_enabled = false;  ///< pcl::StatisticalOutlierRemoval after the voxel grid
  int outlier_k = 16;            ///< its setMeanK
  double outlier_std_mul = 2.0;  ///< its setStddevMulThresh
};

struct PeerResult {
  double voxel_ms = 0, outlier_ms = 0, normals_ms = 0, upd_ms = 0, total_ms = 0;
  core::PointCloud cloud;  ///< the cloud PCL scored (after its voxel grid), for comparisons
  core::UpdResult upd;     ///< r, zeta and k per point of cloud, as computeUpd defines them
};

/// Voxel grid (optional), StatisticalOutlierRemoval (optional), NormalEstimation (KdTreeFLANN radius search, normals oriented by
/// upd::orientNormal as the UPD needs), then for every point a second radius search summing
/// the neighbours' normals (eqs. 6-8). Non-finite input points are dropped first (untimed).
PeerResult runPclPipeline(const core::PointCloud& input, const PeerSettings& settings);

struct IntegralPeerResult {
  double ms = 0;          ///< compute() alone
  std::size_t valid = 0;  ///< pixels with a finite normal
};

/// pcl::IntegralImageNormalEstimation (COVARIANCE_MATRIX, PCL's PCA method) on an organized
/// cloud, with max_depth_change_factor and normal_smoothing_size as given.
IntegralPeerResult runPclIntegralNormals(const core::PointCloud& organized, float max_depth_change_factor,
                                         float normal_smoothing_size);

}  // namespace upd::bench
