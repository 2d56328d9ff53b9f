#include "upd/core/floor_plane.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <sstream>

namespace upd::core {

void FloorPlaneParams::validate() const {
  requireParam(ransac_iterations > 0, "FloorPlaneParams", "ransac_iterations", ransac_iterations,
               "must be > 0");
  requireParam(std::isfinite(inlier_distance_m) && inlier_distance_m > 0, "FloorPlaneParams",
               "inlier_distance_m", inlier_distance_m, "must be > 0");
  requireParam(std::isfinite(max_tilt_rad) && max_tilt_rad > 0 && max_tilt_rad < 85 * kDegToRad,
               "FloorPlaneParams", "max_tilt_deg", max_tilt_rad * kRadToDeg,
               "must be in (0, 85)");
  requireParam(std::isfinite(min_height_m) && min_height_m >= 0, "FloorPlaneParams",
               "min_height_m", min_height_m, "must be >= 0");
  requireParam(std::isfinite(max_height_m) && max_height_m > min_height_m, "FloorPlaneParams",
               "max_height_m", max_height_m, "must be > min_height_m");
  requireParam(std::isfinite(min_inlier_share) && min_inlier_share >= 0 && min_inlier_share < 1,
               "FloorPlaneParams", "min_inlier_share", min_inlier_share, "must be in [0, 1)");
  requireParam(min_inliers >= 3, "FloorPlaneParams", "min_inliers", min_inliers, "must be >= 3");
  requireParam(std::isfinite(max_below_ratio) && max_below_ratio >= 0, "FloorPlaneParams",
               "max_below_ratio", max_below_ratio, "must be >= 0");
  requireParam(std::isfinite(min_area_m2) && min_area_m2 >= 0, "FloorPlaneParams",
               "min_area_m2", min_area_m2, "must be >= 0");
  requireParam(max_sample_points >= 100, "FloorPlaneParams", "max_sample_points",
               max_sample_points, "must be >= 100");
  requireParam(seed >= 0, "FloorPlaneParams", "seed", seed, "must be >= 0");
}

namespace {

using Points = std::vector<Eigen::Vector3d>;

struct Plane {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  double d = 0;
  double distance(const Eigen::Vector3d& p) const { return std::abs(n.dot(p) + d); }
};

// A plane oriented up (the camera, at the origin, on its positive side) that a floor under the
// camera may be: its normal near the prior up and the camera at a plausible height.
bool plausible(Plane& pl, const Eigen::Vector3d& up, const FloorPlaneParams& p) {
  if (pl.d < 0) {
    pl.n = -pl.n;
    pl.d = -pl.d;
  }
  return pl.n.dot(up) >= std::cos(p.max_tilt_rad) && pl.d >= p.min_height_m &&
         pl.d <= p.max_height_m;
}

// Every finite point, and up to max_sample_points of those below the camera (by the prior up)
// for the hypotheses, evenly strided so that they keep the cloud's order.
void gather(const std::vector<const PointCloud*>& clouds, const Eigen::Vector3d& up,
            const FloorPlaneParams& p, Points& all, Points& below) {
  for (const PointCloud* c : clouds) {
    for (std::size_t i = 0; i < c->size(); ++i) {
      if (!c->isFinite(i)) continue;
      all.push_back(c->point(i).cast<double>());
      if (all.back().dot(up) < -p.min_height_m) below.push_back(all.back());
    }
  }
  const auto cap = static_cast<std::size_t>(p.max_sample_points);
  if (below.size() > cap) {
    const double stride = static_cast<double>(below.size()) / cap;
    for (std::size_t i = 0; i < cap; ++i) below[i] = below[static_cast<std::size_t>(i * stride)];
    below.resize(cap);
  }
}

struct Support {
  std::size_t on = 0;     ///< within tol of the plane
  std::size_t under = 0;  ///< more than 3 tol under it
};

Support support(const Points& pts, const Plane& pl, double tol) {
  Support s;
  for (const auto& q : pts) {
    const double h = pl.n.dot(q) + pl.d;
    s.on += std::abs(h) <= tol ? 1 : 0;
    s.under += h < -3 * tol ? 1 : 0;
  }
  return s;
}

// RANSAC over the points below the camera: the plausible plane with the most inliers net of
// the points under it.
std::optional<Plane> ransac(const Points& below, const Eigen::Vector3d& up,
                            const FloorPlaneParams& p, std::mt19937& rng) {
  std::optional<Plane> best;
  double best_score = 0;
  const std::size_t n = below.size();
  const auto window = static_cast<long>(std::max<std::size_t>(8, n / 40));
  std::uniform_int_distribution<std::size_t> pick(0, n - 1);
  std::uniform_int_distribution<long> near(-window, window);
  const auto neighbour = [&](std::size_t i) {  // within the window, clamped to the sample
    const long j = static_cast<long>(i) + near(rng);
    return static_cast<std::size_t>(std::clamp(j, 0L, static_cast<long>(n) - 1));
  };
  for (int it = 0; it < p.ransac_iterations; ++it) {
    const std::size_t ia = pick(rng);
    const bool local = it % 2 == 1;
    const Eigen::Vector3d& a = below[ia];
    const Eigen::Vector3d& b = below[local ? neighbour(ia) : pick(rng)];
    const Eigen::Vector3d& c = below[local ? neighbour(ia) : pick(rng)];
    Plane pl;
    pl.n = (b - a).cross(c - a);
    const double norm = pl.n.norm();
    if (!(norm > 1e-9)) continue;  // collinear or repeated points
    pl.n /= norm;
    pl.d = -pl.n.dot(a);
    if (!plausible(pl, up, p)) continue;
    const Support s = support(below, pl, p.inlier_distance_m);
    const double score = static_cast<double>(s.on) - static_cast<double>(s.under);
    if (score > best_score) {
      best_score = score;
      best = pl;
    }
  }
  return best;
}

// Least-squares plane through the points within tol of pl (smallest-eigenvalue direction of
// their covariance); the inliers' count and RMS distance to the new plane.
Plane refit(const Points& all, const Plane& pl, double tol, std::size_t& inliers, double& rms,
            double& area) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sq = Eigen::Matrix3d::Zero();
  std::size_t n = 0;
  for (const auto& q : all) {
    if (pl.distance(q) > tol) continue;
    sum += q;
    sq += q * q.transpose();
    ++n;
  }
  inliers = n;
  rms = area = 0;
  if (n < 3) return pl;
  const Eigen::Vector3d mean = sum / static_cast<double>(n);
  const Eigen::Matrix3d cov = sq / static_cast<double>(n) - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  Plane out;
  out.n = es.eigenvectors().col(0).normalized();
  if (out.n.dot(pl.n) < 0) out.n = -out.n;
  out.d = -out.n.dot(mean);
  rms = std::sqrt(std::max(0.0, es.eigenvalues()(0)));
  // A uniform rectangle of sides a, b has variances a^2/12 and b^2/12 along them.
  area = 12.0 * std::sqrt(std::max(0.0, es.eigenvalues()(1)) * std::max(0.0, es.eigenvalues()(2)));
  return out;
}

std::string describe(const char* what, double value, const char* rule) {
  std::ostringstream os;
  os.precision(3);
  os << what << value << rule;
  return os.str();
}

}  // namespace

FloorPlane fitFloorPlane(const std::vector<const PointCloud*>& clouds_in_camera,
                         const FloorPlaneParams& params, const Eigen::Vector3d& up_prior) {
  params.validate();
  const Eigen::Vector3d up = up_prior.normalized();
  std::mt19937 rng(static_cast<std::uint32_t>(params.seed));
  Points all, below;
  gather(clouds_in_camera, up, params, all, below);
  FloorPlane out;
  out.valid_points = all.size();
  if (below.size() < 3) {
    out.failure = describe("", static_cast<double>(below.size()),
                           " valid points below the camera");
    return out;
  }
  const std::optional<Plane> hypothesis = ransac(below, up, params, rng);
  if (!hypothesis) {
    out.failure = "no plane below the camera within the tilt and height bounds";
    return out;
  }
  Plane pl = *hypothesis;
  for (int pass = 0; pass < 2; ++pass) {
    pl = refit(all, pl, params.inlier_distance_m, out.inliers, out.rms_residual_m, out.area_m2);
  }
  out.normal = pl.n;
  out.offset_m = pl.d;
  out.below = support(all, pl, params.inlier_distance_m).under;
  if (!plausible(pl, up, params)) {
    out.failure = "the refitted plane leaves the tilt or height bounds";
  } else if (out.inliers < static_cast<std::size_t>(params.min_inliers)) {
    out.failure = describe("only ", static_cast<double>(out.inliers),
                           " points on the best plane");
  } else if (out.inlierShare() < params.min_inlier_share) {
    out.failure = describe("only ", 100.0 * out.inlierShare(),
                           " % of the points on the best plane");
  } else if (out.area_m2 < params.min_area_m2) {
    out.failure = describe("the best plane covers only ", out.area_m2,
                           " m^2 (a shelf or a table, not a floor)");
  } else if (static_cast<double>(out.below) > params.max_below_ratio * out.inliers) {
    out.failure = describe("the best plane has ", static_cast<double>(out.below),
                           " points under it (a surface above the floor)");
  } else {
    out.found = true;
  }
  return out;
}

Eigen::Vector3d floorNormalInCamera(double pitch_rad, double roll_rad) {
  return {-std::cos(pitch_rad) * std::sin(roll_rad), -std::cos(pitch_rad) * std::cos(roll_rad),
          -std::sin(pitch_rad)};
}

MountPose mountFromFloor(const FloorPlane& plane) {
  const Eigen::Vector3d& n = plane.normal;
  MountPose m;
  m.height_m = plane.offset_m;
  m.pitch_rad = std::asin(std::clamp(-n.z(), -1.0, 1.0));
  m.roll_rad = std::atan2(-n.x(), -n.y());
  return m;
}

}  // namespace upd::core
