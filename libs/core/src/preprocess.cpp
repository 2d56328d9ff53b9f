#include "upd/core/preprocess.h"

#include "preprocess_internal.h"
#include "upd/core/openmp.h"

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

namespace detail {

namespace {

// The kept points of c's [b, e) into out from its point at (out may be c: a point then moves
// only to a place already read).
void copyKept(const PointCloud& c, const std::vector<char>& keep, std::size_t b, std::size_t e,
              std::size_t at, PointCloud& out) {
  const bool colour = c.hasColor();
  for (std::size_t i = b; i < e; ++i) {
    if (!keep[i]) continue;
    out.x[at] = c.x[i], out.y[at] = c.y[i], out.z[at] = c.z[i];
    if (colour) out.r[at] = c.r[i], out.g[at] = c.g[i], out.b[at] = c.b[i];
    ++at;
  }
}

}  // namespace

void compactInPlace(PointCloud& c, const std::vector<char>& keep) {
  const bool colour = c.hasColor();
  const std::size_t n = c.size();
  const int most = std::min(openmp::maxThreads(), 64);
  if (n <= 16384 || most == 1) {  // (in place: a point moves only to a place already read)
    std::size_t m = 0;
    for (std::size_t i = 0; i < n; ++i) m += keep[i] ? 1 : 0;
    copyKept(c, keep, 0, n, 0, c);
    c.x.resize(m), c.y.resize(m), c.z.resize(m);
    if (colour) c.r.resize(m), c.g.resize(m), c.b.resize(m);
    c.width = m, c.height = 1;
    return;
  }
  // On the team: each thread counts the kept points of its static share, then copies them,
  // after those of the shares before, into the calling thread's scratch cloud, whose buffers
  // then trade places with c's (both keep their capacity from call to call).
  thread_local PointCloud scratch_cloud;
  thread_local std::vector<std::size_t> kept_counts;
  PointCloud& scratch = scratch_cloud;  // (the calling thread's, named in the region)
  std::vector<std::size_t>& before = kept_counts;
  before.assign(static_cast<std::size_t>(most) + 1, 0);
#pragma omp parallel num_threads(most)
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t b = n * me / team, e = n * (me + 1) / team;
    std::size_t kept = 0;
    for (std::size_t i = b; i < e; ++i) kept += keep[i] ? 1 : 0;
    before[static_cast<std::size_t>(me) + 1] = kept;
#pragma omp barrier
#pragma omp single
    {
      for (int t = 0; t < team; ++t) before[t + 1] += before[t];
      scratch.resize(before[team], colour);
    }
    copyKept(c, keep, b, e, before[static_cast<std::size_t>(me)], scratch);
  }
  c.x.swap(scratch.x), c.y.swap(scratch.y), c.z.swap(scratch.z);
  if (colour) c.r.swap(scratch.r), c.g.swap(scratch.g), c.b.swap(scratch.b);
  c.width = c.x.size(), c.height = 1;
}

}  // namespace detail

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

using detail::RangeBoxTest;

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
  detail::voxelize(in, voxel_m, nullptr, out);
  return out;
}

namespace {
// The count, sum and sum of squares of the finite values of v[b, e), in order.
struct MeanSums {
  std::size_t n = 0;
  double s = 0, s2 = 0;
  void add(const double* v, std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      if (std::isnan(v[i])) continue;
      s += v[i], s2 += v[i] * v[i], ++n;
    }
  }
};

// The outlier filter's verdict per point: its mean neighbour distance within mu + std_mul sigma
// (the calling thread's buffer, valid until its next call). On the team from 16,384 points:
// the sums by blocks of kSumBlock points, each block's in order and the blocks' in order (the
// same limit on any number of threads), then each thread's share of the verdicts, the share
// compactInPlace reads on the same thread.
const std::vector<char>& outlierKeepMask(const PointCloud& in, int k, double std_mul) {
  requireParam(k >= 1, "PreprocessParams", "outlier_k", k, "must be >= 1");
  thread_local std::vector<double> mean_dist;  // (kept from call to call, as keep)
  thread_local std::vector<char> keep;
  thread_local std::vector<MeanSums> block_sums;
  meanNeighbourDistances(in, k, mean_dist);
  const std::size_t N = in.size();
  constexpr std::size_t kSumBlock = 4096;
  const std::size_t n_blocks = (N + kSumBlock - 1) / kSumBlock;
  keep.resize(N);
  block_sums.assign(n_blocks, MeanSums{});
  // (Plain pointers: char stores alias the vectors, and the thread_locals are the calling
  // thread's.)
  const double* m = mean_dist.data();
  char* k_out = keep.data();
  MeanSums* sums = block_sums.data();
  double limit = 0;
#pragma omp parallel if (N > 16384)
  {
#pragma omp for schedule(static)
    for (std::size_t b = 0; b < n_blocks; ++b) {
      sums[b].add(m, b * kSumBlock, std::min(N, (b + 1) * kSumBlock));
    }
#pragma omp single
    {
      MeanSums all;
      for (std::size_t b = 0; b < n_blocks; ++b) {
        all.n += sums[b].n, all.s += sums[b].s, all.s2 += sums[b].s2;
      }
      const double n = static_cast<double>(all.n);
      const double mu = all.s / n;
      // (No finite value: no point is kept.)
      limit = all.n == 0 ? -std::numeric_limits<double>::infinity()
                         : mu + std_mul * std::sqrt(std::max(0.0, all.s2 / n - mu * mu));
    }
    const auto team = static_cast<std::size_t>(openmp::teamSize());
    const auto me = static_cast<std::size_t>(openmp::threadIndex());
    for (std::size_t i = N * me / team; i < N * (me + 1) / team; ++i) {
      // A point alone has no neighbour distance: it is an outlier by definition.
      k_out[i] = !std::isnan(m[i]) && m[i] <= limit;
    }
  }
  return keep;
}
}  // namespace

PointCloud removeStatisticalOutliers(const PointCloud& in, int k, double std_mul) {
  return selectPoints(in, outlierKeepMask(in, k, std_mul));
}

PointCloud preprocess(const PointCloud& in, const PreprocessParams& p, PreprocessStats* stats) {
  if (p.voxel_enabled) {  // (in one pass: preprocessVoxelized)
    PointCloud out;
    preprocess(in, p, out, stats);
    return out;
  }
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
  st.after_voxel = after_crop;
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
// cropRange of an organized cloud into out (its buffers reused) in one pass: the points outside
// the range or the box, and the non-finite ones, become NaN (the same tests, in the same
// precision). In the static shares of the other frame stages.
detail::CropCounts cropOrganized(const PointCloud& in, const PreprocessParams& p,
                                 PointCloud& out) {
  const std::size_t n = in.size();
  detail::copyAllButPoints(in, out);
  const detail::KeyPassParams k = detail::rangeBoxBounds(&p, in.sensor_origin);
  std::size_t finite = 0, kept = 0;
#pragma omp parallel if (n > 65536) reduction(+ : finite, kept)
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t b = n * me / team, e = n * (me + 1) / team;
    const detail::CropCounts c = detail::cropCopy(in.x.data() + b, in.y.data() + b,
                                                  in.z.data() + b, e - b, k, out.x.data() + b,
                                                  out.y.data() + b, out.z.data() + b);
    finite += c.finite;
    kept += c.kept;
  }
  return {finite, kept};
}
}  // namespace

namespace {
// The chain with the voxel grid into out: the cut-off and the voxel grid in one pass over the
// input, the outlier filter on the centroids in place. The same points and centroids as the
// steps one after the other (cropRange, voxelDownsample, removeStatisticalOutliers).
void preprocessVoxelized(const PointCloud& in, const PreprocessParams& p, PointCloud& out,
                         PreprocessStats& st) {
  st.points_in = in.size();
  const RangeBoxTest test(p, in.sensor_origin);
  const detail::CropCounts c =
      detail::voxelize(in, p.voxel_m, test.enabled() ? &test : nullptr, out);
  st.non_finite = in.size() - c.finite;
  st.range_removed = c.finite - c.kept;
  st.after_voxel = out.size();
  if (p.outlier_enabled && !out.empty()) {
    detail::compactInPlace(out, outlierKeepMask(out, p.outlier_k, p.outlier_std_mul));
    st.outliers_removed = st.after_voxel - out.size();
  }
  st.points_out = out.size();
}
}  // namespace

void preprocess(const PointCloud& in, const PreprocessParams& p, PointCloud& out,
                PreprocessStats* stats) {
  if (p.voxel_enabled) {
    p.validate();
    PreprocessStats st;
    preprocessVoxelized(in, p, out, st);
    if (stats) *stats = st;
    return;
  }
  // The outlier filter and an unorganized cloud's compaction build new clouds; the rest (a
  // sensor-rate config: the range cut alone, or nothing) reuses out's buffers.
  if (p.outlier_enabled ||
      ((p.range_enabled || p.box_enabled) && !in.isOrganized())) {
    out = preprocess(in, p, stats);
    return;
  }
  p.validate();
  PreprocessStats st;
  st.points_in = in.size();
  if ((p.range_enabled || p.box_enabled) && &out != &in) {
    const detail::CropCounts c = cropOrganized(in, p, out);  // as preprocess() counts
    st.non_finite = in.size() - c.finite;
    st.range_removed = c.finite - c.kept;
    st.after_voxel = c.kept;
    st.points_out = out.size();
  } else if (p.range_enabled || p.box_enabled) {  // in place
    out = preprocess(in, p, &st);
  } else {
    st.non_finite = in.size() - copyCloud(in, out);
    st.after_voxel = st.points_out = in.size();
  }
  if (stats) *stats = st;
}

}  // namespace upd::core
