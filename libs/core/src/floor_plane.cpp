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
  requireParam(std::isfinite(min_surface_contrast) && min_surface_contrast >= 0 &&
                   min_surface_contrast <= 1,
               "FloorPlaneParams", "min_surface_contrast", min_surface_contrast,
               "must be in [0, 1]");
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
// for the hypotheses, picked with a fixed seed.
void gather(const std::vector<const PointCloud*>& clouds, const Eigen::Vector3d& up,
            const FloorPlaneParams& p, std::mt19937& rng, Points& all, Points& below) {
  for (const PointCloud* c : clouds) {
    for (std::size_t i = 0; i < c->size(); ++i) {
      if (!c->isFinite(i)) continue;
      all.push_back(c->point(i).cast<double>());
      if (all.back().dot(up) < -p.min_height_m) below.push_back(all.back());
    }
  }
  const auto cap = static_cast<std::size_t>(p.max_sample_points);
  if (below.size() > cap) {
    std::shuffle(below.begin(), below.end(), rng);
    below.resize(cap);
  }
}

std::size_t countInliers(const Points& pts, const Plane& pl, double tol) {
  std::size_t n = 0;
  for (const auto& q : pts) n += pl.distance(q) <= tol ? 1 : 0;
  return n;
}

// RANSAC over the points below the camera: the plausible plane with the most inliers.
std::optional<Plane> ransac(const Points& below, const Eigen::Vector3d& up,
                            const FloorPlaneParams& p, std::mt19937& rng) {
  std::optional<Plane> best;
  std::size_t best_count = 0;
  std::uniform_int_distribution<std::size_t> pick(0, below.size() - 1);
  for (int it = 0; it < p.ransac_iterations; ++it) {
    const Eigen::Vector3d &a = below[pick(rng)], &b = below[pick(rng)], &c = below[pick(rng)];
    Plane pl;
    pl.n = (b - a).cross(c - a);
    const double norm = pl.n.norm();
    if (!(norm > 1e-9)) continue;  // collinear or repeated points
    pl.n /= norm;
    pl.d = -pl.n.dot(a);
    if (!plausible(pl, up, p)) continue;
    const std::size_t count = countInliers(below, pl, p.inlier_distance_m);
    if (count > best_count) {
      best_count = count;
      best = pl;
    }
  }
  return best;
}

// Least-squares plane through the points within tol of pl (smallest-eigenvalue direction of
// their covariance); the inliers' count and RMS distance to the new plane.
Plane refit(const Points& all, const Plane& pl, double tol, std::size_t& inliers, double& rms) {
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
  rms = 0;
  if (n < 3) return pl;
  const Eigen::Vector3d mean = sum / static_cast<double>(n);
  const Eigen::Matrix3d cov = sq / static_cast<double>(n) - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  Plane out;
  out.n = es.eigenvectors().col(0).normalized();
  if (out.n.dot(pl.n) < 0) out.n = -out.n;
  out.d = -out.n.dot(mean);
  rms = std::sqrt(std::max(0.0, es.eigenvalues()(0)));
  return out;
}

std::string describe(const char* what, double value, const char* rule) {
  std::ostringstream os;
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
  gather(clouds_in_camera, up, params, rng, all, below);
  FloorPlane out;
  out.valid_points = all.size();
  if (below.size() < 3) {
    out.failure = describe("no floor: ", static_cast<double>(below.size()),
                           " valid points below the camera");
    return out;
  }
  const std::optional<Plane> hypothesis = ransac(below, up, params, rng);
  if (!hypothesis) {
    out.failure = "no floor: no plane below the camera within the tilt and height bounds";
    return out;
  }
  Plane pl = *hypothesis;
  for (int pass = 0; pass < 2; ++pass) {
    pl = refit(all, pl, params.inlier_distance_m, out.inliers, out.rms_residual_m);
  }
  out.normal = pl.n;
  out.offset_m = pl.d;
  const std::size_t band = countInliers(all, pl, 3 * params.inlier_distance_m);
  out.surface_contrast = band ? static_cast<double>(out.inliers) / band : 0.0;
  if (!plausible(pl, up, params)) {
    out.failure = "no floor: the refitted plane leaves the tilt or height bounds";
  } else if (out.inliers < static_cast<std::size_t>(params.min_inliers)) {
    out.failure = describe("no floor: only ", static_cast<double>(out.inliers),
                           " points on the best plane");
  } else if (out.inlierShare() < params.min_inlier_share) {
    out.failure = describe("no floor: only ", 100.0 * out.inlierShare(),
                           " % of the points on the best plane");
  } else if (out.surface_contrast < params.min_surface_contrast) {
    out.failure = describe("no floor: the best plane is no surface (only ",
                           100.0 * out.surface_contrast,
                           " % of the points near it lie on it)");
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
