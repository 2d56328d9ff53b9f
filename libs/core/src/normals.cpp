#include "upd/core/normals.h"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <limits>

namespace upd::core {

void NormalParams::validate() const {
  requireParam(std::isfinite(radius_m) && radius_m > 0, "NormalParams", "radius_m", radius_m,
               "must be > 0");
  requireParam(knn == 0 || knn >= 3, "NormalParams", "knn", knn, "must be 0 (radius) or >= 3");
  requireParam(enumName(kNormalWeightingNames, weighting) != nullptr, "NormalParams", "weighting",
               static_cast<int>(weighting), "must be uniform or gaussian");
  requireParam(vertical_band_rad >= 0 && vertical_band_rad < 0.5 * M_PI, "NormalParams",
               "vertical_band_deg", vertical_band_rad * kRadToDeg, "must be in [0, 90)");
  requireParam(fast_block_px >= 1 && fast_block_px <= 16, "NormalParams", "fast_block_px",
               fast_block_px, "must be in [1, 16]");
  requireParam(fast_scan_px >= 1 && fast_scan_px <= 193, "NormalParams", "fast_scan_px",
               fast_scan_px, "must be in [1, 193]");
  requireParam(std::isfinite(max_depth_jump_ratio) && max_depth_jump_ratio > 0, "NormalParams",
               "max_depth_jump_ratio", max_depth_jump_ratio, "must be > 0");
}

bool pcaNormal(const PointCloud& cloud, const std::vector<std::uint32_t>& neighbours,
               const std::vector<float>& weights, Eigen::Vector3f& n, float& curvature) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  n.setConstant(nan);
  curvature = nan;
  if (neighbours.size() < 3) return false;
  // Moments relative to the first neighbour: no cancellation far from the origin.
  const Eigen::Vector3d ref = cloud.point(neighbours[0]).cast<double>();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum_sq = Eigen::Matrix3d::Zero();
  double w_total = 0;
  for (std::size_t j = 0; j < neighbours.size(); ++j) {
    const double w = weights.empty() ? 1.0 : weights[j];
    const Eigen::Vector3d d = cloud.point(neighbours[j]).cast<double>() - ref;
    sum += w * d;
    sum_sq.noalias() += w * d * d.transpose();
    w_total += w;
  }
  if (!(w_total > 0)) return false;
  const Eigen::Vector3d mean = sum / w_total;
  // Eq. 4: C = 1/sum(xi) * sum xi (p_i - p_bar)(p_i - p_bar)^T.
  const Eigen::Matrix3d cov = sum_sq / w_total - mean * mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  if (es.info() != Eigen::Success) return false;
  const Eigen::Vector3d ev = es.eigenvalues();  // ascending
  const double trace = ev.sum();
  // A collinear (or single-point) neighbourhood has no plane: lambda_1 vanishes.
  if (!(trace > 0) || ev[1] <= 1e-10 * trace) return false;
  n = es.eigenvectors().col(0).cast<float>();  // eq. 5: smallest eigenvalue
  n.normalize();
  curvature = static_cast<float>(std::max(0.0, ev[0]) / trace);
  return true;
}

Eigen::Vector3f orientNormal(const Eigen::Vector3f& n, const Eigen::Vector3f& point,
                             const Eigen::Vector3f& sensor_origin, const Eigen::Vector3f& up,
                             double vertical_band_rad) {
  return NormalOrienter(sensor_origin, up, vertical_band_rad)(n, point);
}

Normals computeNormals(const PointCloud& cloud, const KdTree& tree, const NormalParams& params,
                       const Eigen::Vector3f& up) {
  params.validate();
  const std::size_t n_pts = cloud.size();
  Normals out = Normals::unset(n_pts);
  const float radius = static_cast<float>(params.radius_m);
  const bool gaussian = params.weighting == NormalWeighting::Gaussian;
  const float sigma = params.knn > 0 ? 0.f : 0.5f * radius;
  std::size_t invalid = 0;

#pragma omp parallel reduction(+ : invalid)
  {
    std::vector<std::uint32_t> nb;
    std::vector<float> dist_sq, weights;
#pragma omp for schedule(dynamic, 256)
    for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n_pts); ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      if (!cloud.isFinite(i)) {
        ++invalid;
        continue;
      }
      const Eigen::Vector3f p = cloud.point(i);
      if (params.knn > 0) {
        tree.knnSearch(p, params.knn, nb, gaussian ? &dist_sq : nullptr);
      } else {
        tree.radiusSearch(p, radius, nb);
      }
      weights.clear();
      if (gaussian) {
        float s = sigma;
        if (params.knn > 0) s = 0.5f * std::sqrt(dist_sq.empty() ? 0.f : dist_sq.back());
        const float inv = s > 0.f ? 1.f / (2.f * s * s) : 0.f;
        weights.resize(nb.size());
        for (std::size_t j = 0; j < nb.size(); ++j) {
          weights[j] = std::exp(-(cloud.point(nb[j]) - p).squaredNorm() * inv);
        }
      }
      Eigen::Vector3f n;
      float curv;
      if (!pcaNormal(cloud, nb, weights, n, curv)) {
        ++invalid;
        continue;
      }
      n = orientNormal(n, p, cloud.sensor_origin, up, params.vertical_band_rad);
      out.nx[i] = n.x();
      out.ny[i] = n.y();
      out.nz[i] = n.z();
      out.curvature[i] = curv;
    }
  }
  out.invalid = invalid;
  return out;
}

}  // namespace upd::core
