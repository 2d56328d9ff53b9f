// Per-point scores and the classifier's features (point_features.h).
#include "upd/core/point_features.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <unordered_map>

namespace upd::core {

const char* const kFeatureNames[kFeatureCount] = {
    "zeta_small",       "upd_slope_small",  "roughness_small", "inclination_small",
    "zeta",             "upd_slope",        "roughness",       "inclination",
    "zeta_large",       "upd_slope_large",  "roughness_large", "inclination_large",
    "normal_slope",     "height_range",     "height_spread",   "density",
    "range"};

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

float angleToUp(const Eigen::Vector3f& v, const Eigen::Vector3f& up) {
  const float n = v.norm();
  if (!(n > 0.f)) return kNaN;
  return std::acos(std::clamp(v.dot(up) / n, -1.f, 1.f));
}

RadiusScores scoresAt(const PointCloud& cloud, const KdTree& tree, const Normals& normals,
                      const Eigen::Vector3f& up, double radius_m, int min_neighbors) {
  RadiusScores s;
  s.radius_m = radius_m;
  UpdParams upd;
  upd.radius_m = radius_m;
  upd.method = UpdMethod::Exact;
  s.upd = computeUpd(cloud, tree, normals, upd);
  s.upd_slope_rad.assign(cloud.size(), kNaN);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (s.upd.isValid(i)) s.upd_slope_rad[i] = angleToUp(s.upd.r(i), up);
  }
  BaselineParams base;
  base.radius_m = radius_m;
  base.min_neighbors = min_neighbors;
  s.baselines = computeBaselines(cloud, tree, up, base);
  return s;
}

float orMissing(float v) { return std::isfinite(v) ? v : -1.f; }

}  // namespace

void FeatureParams::validate() const {
  requireParam(radius_small_m > 0 && radius_small_m <= radius_m, "FeatureParams",
               "radius_small_m", radius_small_m, "must be > 0 and <= radius_m");
  requireParam(radius_m <= radius_large_m, "FeatureParams", "radius_m", radius_m,
               "must be <= radius_large_m");
  requireParam(radius_large_m <= 5.0, "FeatureParams", "radius_large_m", radius_large_m,
               "must be <= 5");
  requireParam(cell_m > 0 && cell_m <= 10, "FeatureParams", "cell_m", cell_m, "must be in (0, 10]");
  requireParam(min_neighbors >= 3, "FeatureParams", "min_neighbors", min_neighbors, "must be >= 3");
}

const RadiusScores& PointScores::at(double radius_m) const {
  for (const auto& r : radii) {
    if (r.radius_m == radius_m) return r;
  }
  throw std::invalid_argument("PointScores: no scores at d_m = " + std::to_string(radius_m));
}

std::vector<std::uint32_t> columnIndex(const PointCloud& cloud, const Eigen::Vector3f& up,
                                       double cell_m, std::size_t& columns) {
  const Eigen::Vector3f e1 = up.unitOrthogonal(), e2 = up.cross(e1);
  std::unordered_map<std::uint64_t, std::uint32_t> dense;
  std::vector<std::uint32_t> index(cloud.size(), kNoColumn);
  const auto cellOf = [&](float v) {
    return static_cast<std::uint32_t>(static_cast<std::int32_t>(std::floor(v / cell_m)));
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.isFinite(i)) continue;
    const Eigen::Vector3f p = cloud.point(i);
    const std::uint64_t key = (std::uint64_t(cellOf(p.dot(e1))) << 32) | cellOf(p.dot(e2));
    index[i] = dense.emplace(key, static_cast<std::uint32_t>(dense.size())).first->second;
  }
  columns = dense.size();
  return index;
}

void columnHeightStats(const PointCloud& cloud, const Eigen::Vector3f& up, double cell_m,
                       std::vector<float>& range_m, std::vector<float>& spread_m) {
  struct Column {
    float lo = std::numeric_limits<float>::infinity(), hi = -lo;
    double sum = 0, sum_sq = 0;
    std::size_t n = 0;
  };
  std::size_t count = 0;
  const std::vector<std::uint32_t> column = columnIndex(cloud, up, cell_m, count);
  std::vector<Column> columns(count);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (column[i] == kNoColumn) continue;
    Column& c = columns[column[i]];
    const float h = cloud.point(i).dot(up);
    c.lo = std::min(c.lo, h);
    c.hi = std::max(c.hi, h);
    c.sum += h;
    c.sum_sq += double(h) * h;
    ++c.n;
  }
  range_m.assign(cloud.size(), kNaN);
  spread_m.assign(cloud.size(), kNaN);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (column[i] == kNoColumn) continue;
    const Column& c = columns[column[i]];
    const double mean = c.sum / c.n;
    range_m[i] = c.hi - c.lo;
    spread_m[i] = static_cast<float>(std::sqrt(std::max(0.0, c.sum_sq / c.n - mean * mean)));
  }
}

PointScores computePointScores(const PointCloud& cloud, const KdTree& tree,
                               const Normals& normals, const Eigen::Vector3f& up,
                               const std::vector<double>& radii_m, double cell_m,
                               int min_neighbors) {
  PointScores s;
  for (double r : radii_m) s.radii.push_back(scoresAt(cloud, tree, normals, up, r, min_neighbors));
  s.normal_slope_rad.assign(cloud.size(), kNaN);
  s.range_m.assign(cloud.size(), kNaN);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (normals.isValid(i)) {
      s.normal_slope_rad[i] = std::acos(std::min(1.f, std::abs(normals.normal(i).dot(up))));
    }
    if (cloud.isFinite(i)) s.range_m[i] = (cloud.point(i) - cloud.sensor_origin).norm();
  }
  columnHeightStats(cloud, up, cell_m, s.height_range_m, s.height_spread_m);
  return s;
}

std::vector<float> featuresOf(const PointScores& s, const FeatureParams& params) {
  const std::size_t n = s.range_m.size();
  std::vector<float> f(n * kFeatureCount, -1.f);
  const std::vector<double> radii = params.radii();
  const double disc_m2 = 3.14159265358979 * params.radius_small_m * params.radius_small_m;
  for (std::size_t j = 0; j < radii.size(); ++j) {
    const RadiusScores& r = s.at(radii[j]);
    for (std::size_t i = 0; i < n; ++i) {
      float* row = &f[i * kFeatureCount + 4 * j];
      row[0] = orMissing(r.upd.zeta[i]);
      row[1] = orMissing(r.upd_slope_rad[i]);
      row[2] = orMissing(r.baselines.roughness_m[i]);
      row[3] = orMissing(r.baselines.inclination_rad[i]);
    }
  }
  const RadiusScores& small = s.at(params.radius_small_m);
  for (std::size_t i = 0; i < n; ++i) {
    float* row = &f[i * kFeatureCount + 12];
    row[0] = orMissing(s.normal_slope_rad[i]);
    row[1] = orMissing(s.height_range_m[i]);
    row[2] = orMissing(s.height_spread_m[i]);
    row[3] = small.upd.k[i] > 0 ? static_cast<float>(small.upd.k[i] / disc_m2) : -1.f;
    row[4] = orMissing(s.range_m[i]);
  }
  return f;
}

std::vector<float> computeFeatures(const PointCloud& cloud, const Normals& normals,
                                   const Eigen::Vector3f& up, const FeatureParams& params) {
  params.validate();
  const KdTree tree(cloud);
  const PointScores s = computePointScores(cloud, tree, normals, up, params.radii(),
                                           params.cell_m, params.min_neighbors);
  return featuresOf(s, params);
}

}  // namespace upd::core
