#include "pcl_peer.h"

#include <pcl/features/integral_image_normal.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "upd/core/normals.h"

namespace upd::bench {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

pcl::PointCloud<pcl::PointXYZ>::Ptr toPcl(const PointCloud& in, bool keep_layout) {
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

}  // namespace

PeerResult runPclPipeline(const PointCloud& input, const PeerSettings& s) {
  const auto cloud = toPcl(input, false);
  PeerResult res;
  const auto t_start = Clock::now();

  auto t0 = Clock::now();
  pcl::PointCloud<pcl::PointXYZ>::Ptr scored = cloud;
  if (s.voxel_enabled) {
    scored = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
    pcl::VoxelGrid<pcl::PointXYZ> grid;
    grid.setInputCloud(cloud);
    const auto leaf = static_cast<float>(s.voxel_m);
    grid.setLeafSize(leaf, leaf, leaf);
    grid.filter(*scored);
  }
  res.voxel_ms = msSince(t0);

  t0 = Clock::now();
  auto tree = std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>();
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimator;
  estimator.setInputCloud(scored);
  estimator.setSearchMethod(tree);
  estimator.setRadiusSearch(s.normal_radius_m);
  estimator.setViewPoint(input.sensor_origin.x(), input.sensor_origin.y(), input.sensor_origin.z());
  pcl::PointCloud<pcl::Normal> normals;
  estimator.compute(normals);
  // The UPD needs the orientation rule of normals.h (up, or towards the sensor near vertical).
  const std::size_t n = scored->size();
  std::vector<Eigen::Vector3f> oriented(n);
  std::vector<char> valid(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& nm = normals[i];
    if (!std::isfinite(nm.normal_x) || !std::isfinite(nm.normal_y) || !std::isfinite(nm.normal_z)) {
      continue;
    }
    const auto& p = (*scored)[i];
    oriented[i] = orientNormal(Eigen::Vector3f(nm.normal_x, nm.normal_y, nm.normal_z),
                               Eigen::Vector3f(p.x, p.y, p.z), input.sensor_origin, s.up,
                               s.vertical_band_rad);
    valid[i] = 1;
  }
  res.normals_ms = msSince(t0);

  // The UPD: a second radius search per point (the tree built by NormalEstimation).
  t0 = Clock::now();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  res.upd.rx.assign(n, nan);
  res.upd.ry.assign(n, nan);
  res.upd.rz.assign(n, nan);
  res.upd.zeta.assign(n, nan);
  res.upd.k.assign(n, 0);
  std::vector<int> indices;
  std::vector<float> dist_sq;
  for (std::size_t i = 0; i < n; ++i) {
    tree->radiusSearch((*scored)[i], s.upd_radius_m, indices, dist_sq);
    double x = 0, y = 0, z = 0;
    std::uint32_t k = 0;
    for (const int j : indices) {
      if (!valid[static_cast<std::size_t>(j)]) continue;
      const Eigen::Vector3f& nj = oriented[static_cast<std::size_t>(j)];
      x += nj.x(), y += nj.y(), z += nj.z();
      ++k;
    }
    if (k < static_cast<std::uint32_t>(s.min_neighbors)) {
      ++res.upd.invalid;
      continue;
    }
    res.upd.rx[i] = static_cast<float>(x);
    res.upd.ry[i] = static_cast<float>(y);
    res.upd.rz[i] = static_cast<float>(z);
    res.upd.zeta[i] = static_cast<float>(std::sqrt(x * x + y * y + z * z) / k);
    res.upd.k[i] = k;
  }
  res.upd_ms = msSince(t0);
  res.total_ms = msSince(t_start);

  res.cloud.sensor_origin = input.sensor_origin;
  res.cloud.reserve(n);
  for (const auto& p : scored->points) res.cloud.push_back(p.x, p.y, p.z);
  return res;
}

IntegralPeerResult runPclIntegralNormals(const PointCloud& organized, float max_depth_change_factor,
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
  const auto t0 = Clock::now();
  estimator.compute(normals);
  IntegralPeerResult res;
  res.ms = msSince(t0);
  for (const auto& nm : normals.points) res.valid += std::isfinite(nm.normal_x) ? 1 : 0;
  return res;
}

}  // namespace upd::bench
