// Surface normals by principal component analysis (paper eqs. 4-5).
//
// The normal of a point is the eigenvector of the smallest eigenvalue of the covariance of its
// neighbourhood about the neighbourhood centroid, optionally weighted by xi_i (eq. 4). It is
// oriented to have a positive component along the up direction; a near-vertical normal (within
// vertical_band_deg of horizontal) is instead oriented towards the sensor origin, so the normals
// of one wall all point the same way. Fewer than 3 neighbours give a NaN normal, counted.
#pragma once

#include "upd/core/kdtree.h"
#include "upd/core/params.h"
#include "upd/core/point_cloud.h"

#include <cstdint>
#include <vector>

namespace upd {

enum class NormalWeighting : int {
  Uniform = 0,   ///< xi_i = 1 (the paper's default)
  Gaussian = 1,  ///< xi_i = exp(-|p_i - p|^2 / (2 (radius/2)^2)): nearer points count more
};

struct NormalParams {
  double radius_m = 0.1;  ///< neighbourhood radius for PCA [m]; used when knn == 0
  int knn = 0;            ///< > 0: use the knn nearest points instead of the radius
  int weighting = static_cast<int>(NormalWeighting::Uniform);  ///< 0 uniform, 1 gaussian (eq. 4 xi)
  /// A normal closer than this to horizontal is oriented towards the sensor [rad].
  double vertical_band_rad = 30.0 * kDegToRad;

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("radius_m", radius_m, "PCA neighbourhood radius [m] (used when knn = 0)");
    v("knn", knn, "if > 0, use the k nearest points instead of the radius");
    v("weighting", weighting, "covariance weights xi (eq. 4): 0 uniform, 1 gaussian");
    v.angleDeg("vertical_band_deg", vertical_band_rad,
               "normals this close to horizontal are oriented towards the sensor [deg]");
  }
};

/// Per-point unit normals; NaN where a normal could not be computed.
struct Normals {
  std::vector<float> nx, ny, nz;
  std::vector<float> curvature;  ///< lambda_0 / (lambda_0 + lambda_1 + lambda_2), NaN if invalid
  std::size_t invalid = 0;       ///< points with a NaN normal (non-finite or < 3 neighbours)

  std::size_t size() const { return nx.size(); }
  bool isValid(std::size_t i) const { return nx[i] == nx[i]; }
  Eigen::Vector3f normal(std::size_t i) const { return {nx[i], ny[i], nz[i]}; }
};

/// PCA normal of a neighbourhood (eqs. 4-5), plain function: returns false and leaves n as NaN
/// for fewer than 3 points or a degenerate (collinear) neighbourhood. weights may be empty.
/// The result is not oriented.
bool pcaNormal(const PointCloud& cloud, const std::vector<std::uint32_t>& neighbours,
               const std::vector<float>& weights, Eigen::Vector3f& n, float& curvature);

/// Orients n by the rule in the header comment. up must be unit length.
Eigen::Vector3f orientNormal(const Eigen::Vector3f& n, const Eigen::Vector3f& point,
                             const Eigen::Vector3f& sensor_origin, const Eigen::Vector3f& up,
                             double vertical_band_rad);

/// Normals of every point of cloud (which tree indexes).
Normals computeNormals(const PointCloud& cloud, const KdTree& tree, const NormalParams& params,
                       const Eigen::Vector3f& up);

}  // namespace upd
