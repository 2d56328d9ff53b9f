#include "pcl_peer.h"

#include <pcl/features/integral_image_normal.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "upd/core/normals.h"
#include "upd/core/stopwatch.h"

namespace core = upd::core;

namespace upd::bench {

namespace {

pcl::PointCloud<pcl::PointXYZ>::Ptr toPcl(const core::PointCloud& in, bool keep_layout) {
  auto out = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  out->points.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (!keep_layout && !in.isFinite(i)) continue;
    out->points.emplace_back(in.x[i], in.y[i], in.z[i]);
  }
  if (keep_layout) {
    out->width = static_cast<std::uint32_t>(in.width);
    out->height = static_cast<std::uint32_t>(in.height);
    out->is_dense = false;
  } else {
    out->width = static_cast<std::uint32_t>(out->points.size());
    out->height = 1;
    out->is_dense = true;
  }
  out->sensor_origin_ =
      Eigen::Vector4f(in.sensor_origin.x(), in.sensor_origin.y(), in.sensor_origin.z(), 0.f);
  return out;
}

using PclCloud = pcl::PointCloud<pcl::PointXYZ>;

// The voxel grid, when enabled; else the input itself.
PclCloud::Ptr voxelGrid(const PclCloud::Ptr& cloud, const PeerSettings& s) {
  if (!s.voxel_enabled) return cloud;
  auto scored = std::make_shared<PclCloud>();
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(cloud);
  const auto leaf = static_cast<float>(s.voxel_m);
  grid.setLeafSize(leaf, leaf, leaf);
  grid.filter(*scored);
  return scored;
}

// The statistical outlier filter, when enabled; else the input itself.
PclCloud::Ptr outlierFilter(const PclCloud::Ptr& cloud, const PeerSettings& s) {
  if (!s.outlier_enabled) return cloud;
  auto kept = std::make_shared<PclCloud>();
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
  sor.setInputCloud(cloud);
  sor.setMeanK(s.outlier_k);
  sor.setStddevMulThresh(s.outlier_std_mul);
  sor.filter(*kept);
  return kept;
}

struct OrientedNormals {
  std::vector<Eigen::Vector3f> normal;
  std::vector<char> valid;
};

// NormalEstimation by radius search on tree, then the orientation rule of normals.h (up, or
// towards the sensor near vertical), which the UPD needs.
OrientedNormals peerNormals(const PclCloud::Ptr& scored,
                            const pcl::search::KdTree<pcl::PointXYZ>::Ptr& tree,
                            const Eigen::Vector3f& sensor_origin, const PeerSettings& s) {
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimator;
  estimator.setInputCloud(scored);
  estimator.setSearchMethod(tree);
  estimator.setRadiusSearch(s.normal_radius_m);
  estimator.setViewPoint(sensor_origin.x(), sensor_origin.y(), sensor_origin.z());
  pcl::PointCloud<pcl::Normal> normals;
  estimator.compute(normals);
  const std::size_t n = scored->size();
  OrientedNormals out{std::vector<Eigen::Vector3f>(n), std::vector<char>(n, 0)};
  for (std::size_t i = 0; i < n; ++i) {
    const auto& nm = normals[i];
    if (!std::isfinite(nm.normal_x) || !std::isfinite(nm.normal_y) || !std::isfinite(nm.normal_z)) {
      continue;
    }
    const auto& p = (*scored)[i];
    out.normal[i] = core::orientNormal(Eigen::Vector3f(nm.normal_x, nm.normal_y, nm.normal_z),
                                 Eigen::Vector3f(p.x, p.y, p.z), sensor_origin, s.up,
                                 s.vertical_band_rad);
    out.valid[i] = 1;
  }
  return out;
}

// The UPD: a second radius search per point (the tree built by NormalEstimation), eqs. 6-8.
core::UpdResult peerUpd(const PclCloud& scored, pcl::search::KdTree<pcl::PointXYZ>& tree,
                  const OrientedNormals& normals, const PeerSettings& s) {
  const std::size_t n = scored.size();
  core::UpdResult upd;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  upd.rx.assign(n, nan);
  upd.ry.assign(n, nan);
  upd.rz.assign(n, nan);
  upd.zeta.assign(n, nan);
  upd.k.assign(n, 0);
  std::vector<int> indices;
  std::vector<float> dist_sq;
  for (std::size_t i = 0; i < n; ++i) {
    tree.radiusSearch(scored[i], s.upd_radius_m, indices, dist_sq);
    double x = 0, y = 0, z = 0;
    std::uint32_t k = 0;
    for (const int j : indices) {
      if (!normals.valid[static_cast<std::size_t>(j)]) continue;
      const Eigen::Vector3f& nj = normals.normal[static_cast<std::size_t>(j)];
      x += nj.x(), y += nj.y(), z += nj.z();
      ++k;
    }
    if (k < static_cast<std::uint32_t>(s.min_neighbors)) {
      ++upd.invalid;
      continue;
    }
    upd.rx[i] = static_cast<float>(x);
    upd.ry[i] = static_cast<float>(y);
    upd.rz[i] = static_cast<float>(z);
    upd.zeta[i] = static_cast<float>(std::sqrt(x * x + y * y + z * z) / k);
    upd.k[i] = k;
  }
  return upd;
}

}  // namespace

PeerResult runPclPipeline(const core::PointCloud& input, const PeerSettings& s) {
  const auto cloud = toPcl(input, false);
  PeerResult res;
  const core::Stopwatch total;
  core::Stopwatch stage;
  const PclCloud::Ptr voxels = voxelGrid(cloud, s);
  res.voxel_ms = stage.elapsedMs();
  stage.restart();
  const PclCloud::Ptr scored = outlierFilter(voxels, s);
  res.outlier_ms = stage.elapsedMs();

  stage.restart();
  auto tree = std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();
  const OrientedNormals normals = peerNormals(scored, tree, input.sensor_origin, s);
  res.normals_ms = stage.elapsedMs();

  stage.restart();
  res.upd = peerUpd(*scored, *tree, normals, s);
  res.upd_ms = stage.elapsedMs();
  res.total_ms = total.elapsedMs();

  res.cloud.sensor_origin = input.sensor_origin;
  res.cloud.reserve(scored->size());
  for (const auto& p : scored->points) res.cloud.push_back(p.x, p.y, p.z);
  return res;
}

IntegralPeerResult runPclIntegralNormals(const core::PointCloud& organized, float max_depth_change_factor,
                                         float normal_smoothing_size) {
  if (!organized.isOrganized()) {
    throw std::invalid_argument("runPclIntegralNormals: the cloud is not organized");
  }
  const auto cloud = toPcl(organized, true);
  pcl::IntegralImageNormalEstimation<pcl::PointXYZ, pcl::Normal> estimator;
  estimator.setNormalEstimationMethod(estimator.COVARIANCE_MATRIX);
  estimator.setMaxDepthChangeFactor(max_depth_change_factor);
  estimator.setNormalSmoothingSize(normal_smoothing_size);
  estimator.setInputCloud(cloud);
  pcl::PointCloud<pcl::Normal> normals;
  const core::Stopwatch watch;
  estimator.compute(normals);
  IntegralPeerResult res;
  res.ms = watch.elapsedMs();
  for (const auto& nm : normals.points) res.valid += std::isfinite(nm.normal_x) ? 1 : 0;
  return res;
}

}  // namespace upd::bench
