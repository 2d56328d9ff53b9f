#include "upd/core/preprocess.h"

#include "fast_cell_map.h"
#include "fast_simd.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace upd::core {

void PreprocessParams::validate() const {
  requireParam(std::isfinite(range_min_m) && range_min_m >= 0, "PreprocessParams", "range_min_m",
               range_min_m, "must be >= 0");
  requireParam(range_max_m > range_min_m, "PreprocessParams", "range_max_m", range_max_m,
               "must be > range_min_m");
  requireParam((box_max_m - box_min_m).minCoeff() > 0, "PreprocessParams", "box_max_m",
               box_max_m, "must be > box_min_m on every axis");
  requireParam(std::isfinite(voxel_m) && voxel_m > 0, "PreprocessParams", "voxel_m", voxel_m,
               "must be > 0");
  requireParam(outlier_k >= 1, "PreprocessParams", "outlier_k", outlier_k, "must be >= 1");
  requireParam(std::isfinite(outlier_std_mul) && outlier_std_mul >= 0, "PreprocessParams",
               "outlier_std_mul", outlier_std_mul, "must be >= 0");
}

namespace {

// Keeps the points where keep[i]: an organized cloud keeps its layout (others become NaN),
// an unorganized one is compacted.
PointCloud selectPoints(const PointCloud& in, const std::vector<char>& keep) {
  PointCloud out;
  out.sensor_origin = in.sensor_origin;
  const bool colour = in.hasColor();
  if (in.isOrganized()) {
    out = in;
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (!keep[i]) out.x[i] = out.y[i] = out.z[i] = nan;
    }
    return out;
  }
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (!keep[i]) continue;
    if (colour) {
      out.push_back(in.x[i], in.y[i], in.z[i], in.r[i], in.g[i], in.b[i]);
    } else {
      out.push_back(in.x[i], in.y[i], in.z[i]);
    }
  }
  return out;
}

}  // namespace

PointCloud dropNonFinite(const PointCloud& in) {
  std::vector<char> keep(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) keep[i] = in.isFinite(i);
  PointCloud unorganized = in;
  unorganized.width = in.size();
  unorganized.height = 1;
  return selectPoints(unorganized, keep);
}

namespace {
// The test of cropRange for a finite point q: within the range of the sensor origin and inside
// the box, each when enabled.
class RangeBoxTest {
 public:
  RangeBoxTest(const PreprocessParams& p, const Eigen::Vector3f& sensor_origin)
      : p_(p),
        origin_(sensor_origin),
        rmin2_(p.range_min_m * p.range_min_m),
        rmax2_(p.range_max_m * p.range_max_m) {}
  bool keeps(const Eigen::Vector3f& q) const {
    if (p_.range_enabled) {
      const double d2 = (q - origin_).cast<double>().squaredNorm();
      if (!(d2 >= rmin2_ && d2 <= rmax2_)) return false;
    }
    return !p_.box_enabled ||
           ((q.array() >= p_.box_min_m.array()).all() && (q.array() <= p_.box_max_m.array()).all());
  }

 private:
  const PreprocessParams& p_;
  Eigen::Vector3f origin_;
  double rmin2_, rmax2_;
};
}  // namespace

PointCloud cropRange(const PointCloud& in, const PreprocessParams& p) {
  std::vector<char> keep(in.size(), 0);
  const RangeBoxTest test(p, in.sensor_origin);
  for (std::size_t i = 0; i < in.size(); ++i) keep[i] = in.isFinite(i) && test.keeps(in.point(i));
  return selectPoints(in, keep);
}

PointCloud voxelDownsample(const PointCloud& in, double voxel_m) {
  requireParam(std::isfinite(voxel_m) && voxel_m > 0, "PreprocessParams", "voxel_m", voxel_m,
               "must be > 0");
  PointCloud out;
  out.sensor_origin = in.sensor_origin;
  // Voxel keys and centroids relative to the first finite point: exact far from the origin.
  std::size_t first = 0;
  while (first < in.size() && !in.isFinite(first)) ++first;
  if (first == in.size()) return out;
  const Eigen::Vector3d ref = in.point(first).cast<double>();
  const double inv = 1.0 / voxel_m;
  // Per voxel, in order of first appearance (the dense index of the flat hash map): the sums
  // of the points relative to ref, of the colours, and the count.
  struct Acc {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double r = 0, g = 0, b = 0;
    std::uint32_t n = 0;
  };
  std::vector<Acc> voxels;
  voxels.reserve(in.size() / 4 + 16);
  detail::CellMap map(in.size() / 4 + 16);
  const bool colour = in.hasColor();
  std::uint64_t last_key = 0;
  Acc* acc = nullptr;  // the voxel of the last point: consecutive points mostly share one
  for (std::size_t i = first; i < in.size(); ++i) {
    if (!in.isFinite(i)) continue;
    const Eigen::Vector3d d = in.point(i).cast<double>() - ref;
    // Checked before the conversion to integers, which is undefined beyond 2^63 (1e30 m).
    const bool in_range = (d * inv).cwiseAbs().maxCoeff() < 1e15;
    const std::int64_t cx = in_range ? detail::floorToInt(d.x() * inv) : 0,
                       cy = in_range ? detail::floorToInt(d.y() * inv) : 0,
                       cz = in_range ? detail::floorToInt(d.z() * inv) : 0;
    if (!in_range || !detail::keyFits(cx, cy, cz)) {
      throw std::invalid_argument(
          "PreprocessParams.voxel_m = " + std::to_string(voxel_m) +
          ": the cloud spans more than 2^20 voxels along an axis; use a larger voxel or a "
          "range cut-off");
    }
    const std::uint64_t key = detail::packKey(cx, cy, cz);
    if (acc == nullptr || key != last_key) {
      bool inserted = false;
      const std::uint32_t id = map.findOrInsert(key, inserted);
      if (inserted) voxels.emplace_back();
      acc = &voxels[id];
      last_key = key;
    }
    acc->sum += d;
    ++acc->n;
    if (colour) {
      acc->r += in.r[i];
      acc->g += in.g[i];
      acc->b += in.b[i];
    }
  }
  // Output in order of first appearance: deterministic.
  out.reserve(voxels.size());
  for (const Acc& v : voxels) {
    const Eigen::Vector3d c = ref + v.sum / v.n;
    if (colour) {
      const auto avg = [&](double s) { return static_cast<std::uint8_t>(std::lround(s / v.n)); };
      out.push_back(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z()),
                    avg(v.r), avg(v.g), avg(v.b));
    } else {
      out.push_back(static_cast<float>(c.x()), static_cast<float>(c.y()),
                    static_cast<float>(c.z()));
    }
  }
  return out;
}

PointCloud removeStatisticalOutliers(const PointCloud& in, int k, double std_mul) {
  requireParam(k >= 1, "PreprocessParams", "outlier_k", k, "must be >= 1");
  const std::vector<double> mean_dist = meanNeighbourDistances(in, k);
  double s = 0, s2 = 0;
  std::size_t n = 0;
  for (const double d : mean_dist) {
    if (std::isnan(d)) continue;
    s += d;
    s2 += d * d;
    ++n;
  }
  std::vector<char> keep(in.size(), 0);
  if (n == 0) return selectPoints(in, keep);
  const double mu = s / n;
  const double sigma = std::sqrt(std::max(0.0, s2 / n - mu * mu));
  const double limit = mu + std_mul * sigma;
  for (std::size_t i = 0; i < in.size(); ++i) {
    // A point alone has no neighbour distance: it is an outlier by definition.
    keep[i] = !std::isnan(mean_dist[i]) && mean_dist[i] <= limit;
  }
  return selectPoints(in, keep);
}

PointCloud preprocess(const PointCloud& in, const PreprocessParams& p, PreprocessStats* stats) {
  p.validate();
  PreprocessStats st;
  st.points_in = in.size();
  const std::size_t finite = in.countFinite();
  st.non_finite = in.size() - finite;
  if (!p.anyEnabled()) {
    st.after_voxel = st.points_out = in.size();
    if (stats) *stats = st;
    return in;
  }
  PointCloud cloud = (p.range_enabled || p.box_enabled) ? cropRange(in, p) : in;
  const std::size_t after_crop = cloud.countFinite();
  st.range_removed = finite - after_crop;
  if (p.voxel_enabled) cloud = voxelDownsample(cloud, p.voxel_m);
  st.after_voxel = cloud.countFinite();
  if (p.outlier_enabled && !cloud.empty()) {
    cloud = removeStatisticalOutliers(cloud, p.outlier_k, p.outlier_std_mul);
    st.outliers_removed = st.after_voxel - cloud.countFinite();
  }
  if (!cloud.isOrganized()) cloud = dropNonFinite(cloud);
  st.points_out = cloud.size();
  if (stats) *stats = st;
  return cloud;
}

namespace {
// cropRange in place on an organized cloud: the points outside the range or the box, and the
// non-finite ones, become NaN (the same tests, in the same precision). Returns the finite points
// left. In the static shares of the other frame stages.
std::size_t cropOrganizedInPlace(PointCloud& c, const PreprocessParams& p) {
  const RangeBoxTest test(p, c.sensor_origin);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::size_t n = c.size();
  float *x = c.x.data(), *y = c.y.data(), *z = c.z.data();
  std::size_t kept = 0;
#pragma omp parallel for schedule(static) if (n > 65536) reduction(+ : kept)
  for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n); ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const Eigen::Vector3f q(x[i], y[i], z[i]);
    // A non-finite point becomes NaN too, as in cropRange.
    if (q.allFinite() && test.keeps(q)) {
      ++kept;
    } else {
      x[i] = y[i] = z[i] = nan;
    }
  }
  return kept;
}
}  // namespace

void preprocess(const PointCloud& in, const PreprocessParams& p, PointCloud& out,
                PreprocessStats* stats) {
  // The voxel grid, the outlier filter and an unorganized cloud's compaction build new clouds;
  // the rest (a sensor-rate config: the range cut alone, or nothing) reuses out's buffers.
  if (p.voxel_enabled || p.outlier_enabled ||
      ((p.range_enabled || p.box_enabled) && !in.isOrganized())) {
    out = preprocess(in, p, stats);
    return;
  }
  p.validate();
  const std::size_t finite = copyCloud(in, out);
  PreprocessStats st;
  st.points_in = in.size();
  st.non_finite = in.size() - finite;
  if (p.range_enabled || p.box_enabled) {
    const std::size_t after_crop = cropOrganizedInPlace(out, p);  // as preprocess() counts
    st.range_removed = finite - after_crop;
    st.after_voxel = after_crop;
    st.points_out = out.size();
  } else {
    st.after_voxel = st.points_out = in.size();
  }
  if (stats) *stats = st;
}

}  // namespace upd::core
