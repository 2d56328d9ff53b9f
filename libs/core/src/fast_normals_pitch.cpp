// The fast normals' pitch profiles (pitchProfiles, fast_normals_internal.h): the angle between
// the rays of neighbouring columns and rows, measured on the frame, that the organized path's
// windows are sized from.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "fast_normals_internal.h"
#include "upd/core/openmp.h"

namespace upd::core::detail {

namespace {

// The chord between the unit rays of pixels i and i + step, i = first + t * step, for t in
// [0, n): the angle between them to 1e-6 at these sizes; NaN where either has no range.
UPD_VECTOR_CLONES
void lineChords(const float* __restrict x, const float* __restrict y, const float* __restrict z,
                const float* __restrict range, std::size_t first, std::size_t step, std::size_t n,
                const Eigen::Vector3f& origin, float* __restrict chord) {
  const float ox = origin.x(), oy = origin.y(), oz = origin.z();
  for (std::size_t t = 0; t < n; ++t) {
    const std::size_t i = first + t * step, j = i + step;
    const float inv_i = 1.f / range[i], inv_j = 1.f / range[j];
    const float dx = (x[i] - ox) * inv_i - (x[j] - ox) * inv_j;
    const float dy = (y[i] - oy) * inv_i - (y[j] - oy) * inv_j;
    const float dz = (z[i] - oz) * inv_i - (z[j] - oz) * inv_j;
    chord[t] = std::sqrt(dx * dx + dy * dy + dz * dz);
  }
}

// The chords of pitchProfiles: between the rays of neighbouring pixels along every 16th line,
// sampled x (len - 1) of them, NaN where a pixel has no range.
std::vector<float> lineChordsOf(const PointCloud& cloud, const float* range, bool along_u) {
  const std::size_t W = cloud.width, H = cloud.height;
  const std::size_t lines = along_u ? H : W, len = along_u ? W : H;
  const std::size_t sampled = (lines + 15) / 16, pairs = len - 1;
  std::vector<float> chords(sampled * pairs);
  // Each thread reads the rows of its static share of the image, as in the stages after: rows
  // are dealt out whole, columns by their pairs' rows. (Reading lines of the image that the
  // other core writes next frame made that write twice as slow.)
#pragma omp parallel
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t k0 = along_u ? sampled * me / team : 0,
                      k1 = along_u ? sampled * (me + 1) / team : sampled;
    const std::size_t t0 = along_u ? 0 : pairs * me / team,
                      t1 = along_u ? pairs : pairs * (me + 1) / team;
    for (std::size_t k = k0; k < k1; ++k) {
      const std::size_t l = 16 * k;
      lineChords(cloud.x.data(), cloud.y.data(), cloud.z.data(), range,
                 along_u ? l * W : l + t0 * W, along_u ? 1 : W, t1 - t0, cloud.sensor_origin,
                 &chords[k * pairs + t0]);
    }
  }
  return chords;
}

// The pitch per column or row from its chords (pairs of them a sampled line): pitchProfiles'.
std::vector<float> pitchFromChords(const std::vector<float>& chords, std::size_t pairs) {
  if (pairs == 0) return {};
  const std::size_t sampled = chords.size() / pairs;
  std::vector<float> lowest(pairs + 1, std::numeric_limits<float>::infinity());
  std::vector<float> all;
  all.reserve(chords.size());
  for (std::size_t k = 0; k < sampled; ++k) {
    for (std::size_t t = 0; t < pairs; ++t) {
      const float a = chords[k * pairs + t];
      if (!(a == a)) continue;
      lowest[t] = std::min(lowest[t], a);
      all.push_back(a);
    }
  }
  if (all.size() < 16) return {};
  auto mid = all.begin() + static_cast<std::ptrdiff_t>(all.size() / 2);
  std::nth_element(all.begin(), mid, all.end());
  const float median = *mid;
  if (!(median > 0.f)) return {};
  for (float& p : lowest) p = std::isfinite(p) ? std::max(p, 0.5f * median) : median;
  return lowest;
}

}  // namespace

// The angular pitch of the sensor per column (along_u: the angle between the rays of columns
// u and u + 1) or per row [rad]: the smallest over every 16th line, so that windows sized from
// it hold the whole ball even where the pitch shrinks (off-axis, by cos^2 of the angle for a
// pinhole camera). Columns without a sample take the median; a pitch below half the median
// (duplicated pixels) is raised to it. Empty when too few pairs are valid.
// Both profiles: the chords by the team, then the two medians one on each thread.
void pitchProfiles(const PointCloud& cloud, const float* range, std::vector<float>& along_u,
                   std::vector<float>& along_v) {
  const std::vector<float> chords_u = lineChordsOf(cloud, range, true);
  const std::vector<float> chords_v = lineChordsOf(cloud, range, false);
#pragma omp parallel sections
  {
#pragma omp section
    along_u = pitchFromChords(chords_u, cloud.width - 1);
#pragma omp section
    along_v = pitchFromChords(chords_v, cloud.height - 1);
  }
}

}  // namespace upd::core::detail
