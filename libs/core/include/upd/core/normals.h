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

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace upd::core {

enum class NormalWeighting : int {
  Uniform = 0,   ///< xi_i = 1 (the paper's default)
  Gaussian = 1,  ///< xi_i = exp(-|p_i - p|^2 / (2 (radius/2)^2)): nearer points count more
};
/// The ini names of NormalWeighting ([NormalParams] weighting); the loader also takes the numbers.
inline constexpr EnumName<NormalWeighting> kNormalWeightingNames[] = {
    {"uniform", NormalWeighting::Uniform}, {"gaussian", NormalWeighting::Gaussian}};

struct NormalParams {
  double radius_m = 0.1;  ///< neighbourhood radius for PCA [m]; used when knn == 0
  int knn = 0;            ///< > 0: use the knn nearest points instead of the radius
  NormalWeighting weighting = NormalWeighting::Uniform;  ///< xi_i of eq. 4
  /// A normal closer than this to horizontal is oriented towards the sensor [rad].
  double vertical_band_rad = 30.0 * kDegToRad;
  /// Fast path on organized clouds (fast_normals.h): one normal is computed per block of
  /// fast_block_px x fast_block_px pixels (at its centre) and shared by the pixels on its
  /// surface in the block and the 8 blocks around it (each takes the nearest in range).
  int fast_block_px = 4;
  /// Fast path on organized clouds: the ball's pixel window is scanned at every pixel up to
  /// this many pixels across, every 2nd row and column up to twice that, every 4th beyond
  /// (near points, whose balls span many pixels). Sampling every 2nd pixel on a quantized Kinect
  /// depth staircase tilts the normals enough to flip labels (docs/PERFORMANCE.md).
  int fast_scan_px = 48;
  /// Fast path on organized clouds: a pixel shares a block centre's normal only when their
  /// ranges differ by at most this fraction of the range [-] (PCL's depth-change factor is 0.02).
  double max_depth_jump_ratio = 0.02;

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("radius_m", radius_m, "PCA neighbourhood radius [m] (used when knn = 0)");
    v("knn", knn, "if > 0, use the k nearest points instead of the radius");
    v.choice("weighting", weighting, kNormalWeightingNames,
             "covariance weights xi (eq. 4): uniform or gaussian; the numbers 0, 1 are also "
             "accepted");
    v.angleDeg("vertical_band_deg", vertical_band_rad,
               "normals this close to horizontal are oriented towards the sensor [deg]");
    v("fast_block_px", fast_block_px,
      "fast path, organized clouds: one normal per block of this many pixels squared, shared "
      "by the pixels on the same surface nearby (1 = a normal per pixel)");
    v("fast_scan_px", fast_scan_px,
      "fast path, organized clouds: windows up to this many pixels across are scanned at "
      "every pixel, up to twice that every 2nd row and column, wider ones every 4th");
    v("max_depth_jump_ratio", max_depth_jump_ratio,
      "fast path, organized clouds: a pixel shares a block centre's normal only if their "
      "ranges differ by at most this fraction of the range");
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

  /// n points, no normal yet (NaN): where the exact and fast paths start.
  static Normals unset(std::size_t n) {
    Normals out;
    out.setUnset(n);
    return out;
  }
  /// The same in place, keeping the buffers' storage.
  void setUnset(std::size_t n) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    nx.assign(n, nan);
    ny.assign(n, nan);
    nz.assign(n, nan);
    curvature.assign(n, nan);
    invalid = 0;
  }
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

/// orientNormal's rule with the sine of the band computed once, for loops over many points.
struct NormalOrienter {
  Eigen::Vector3f sensor_origin, up;  ///< up must be unit length
  float sin_band;                     ///< sin(vertical_band_rad)

  NormalOrienter(const Eigen::Vector3f& origin, const Eigen::Vector3f& unit_up,
                 double vertical_band_rad)
      : sensor_origin(origin), up(unit_up),
        sin_band(std::sin(static_cast<float>(vertical_band_rad))) {}
  Eigen::Vector3f operator()(const Eigen::Vector3f& n, const Eigen::Vector3f& point) const {
    const float along_up = n.dot(up);
    if (std::abs(along_up) > sin_band) return along_up > 0.f ? n : Eigen::Vector3f(-n);
    // Near-vertical surface: towards the sensor so one wall's normals agree.
    return n.dot(sensor_origin - point) >= 0.f ? n : Eigen::Vector3f(-n);
  }
};

/// Normals of every point of cloud (which tree indexes).
Normals computeNormals(const PointCloud& cloud, const KdTree& tree, const NormalParams& params,
                       const Eigen::Vector3f& up);

}  // namespace upd::core
