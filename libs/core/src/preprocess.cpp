#include "upd/core/preprocess.h"

#include "upd/core/kdtree.h"

#include "fast_cell_map.h"
#include "fast_simd.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace upd {

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
    const std::int64_t cx = detail::floorToInt(d.x() * inv), cy = detail::floorToInt(d.y() * inv),
                       cz = detail::floorToInt(d.z() * inv);
    if (!detail::keyFits(cx, cy, cz)) {
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

namespace {

// The cell (x, y, z) of point i in cells of edge 1 / inv_h anchored at point f0, as 64-bit
// integers (detail::keyFits says whether they fit a key).
inline void cellOf(const PointCloud& in, std::uint32_t i, std::uint32_t f0, double inv_h,
                   std::int64_t (&c)[3]) {
  c[0] = detail::floorToInt(static_cast<double>(in.x[i] - in.x[f0]) * inv_h);
  c[1] = detail::floorToInt(static_cast<double>(in.y[i] - in.y[f0]) * inv_h);
  c[2] = detail::floorToInt(static_cast<double>(in.z[i] - in.z[f0]) * inv_h);
}

// The finite points binned into cubic cells of edge h (anchored at the first finite point, as
// the fast UPD's lattice): cell ids from a flat hash map, and the points' coordinates relative
// to the anchor sorted by cell (counting sort), with their cloud indices.
struct PointGrid {
  double h = 1, inv_h = 1;
  float ox = 0, oy = 0, oz = 0;  // anchor
  detail::CellMap map;
  std::vector<std::int32_t> cell_xyz;  // 3 per cell
  std::vector<std::uint32_t> start;    // n_cells + 1
  std::vector<float> x, y, z;          // by cell
  std::vector<std::uint32_t> index;    // by cell: the cloud's index

  // Squared distance from (qx, qy, qz) to the box of cell c (0 inside).
  float boxDistance2(std::uint32_t c, float qx, float qy, float qz) const {
    const float q[3] = {qx, qy, qz};
    float d2 = 0.f;
    for (int a = 0; a < 3; ++a) {
      const auto lo = static_cast<float>(cell_xyz[3 * c + a] * h);
      const auto hi = static_cast<float>((cell_xyz[3 * c + a] + 1) * h);
      const float d = q[a] < lo ? lo - q[a] : (q[a] > hi ? q[a] - hi : 0.f);
      d2 += d * d;
    }
    // (Shrunk by a rounding margin: a cell is skipped only when it is certainly farther.)
    return d2 * (1.f - 1e-5f);
  }
  std::uint32_t find(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
    return detail::keyFits(cx, cy, cz) ? map.find(detail::packKey(cx, cy, cz)) : detail::kNoIndex;
  }
};

// Bins the finite points at edge h; false when a point lies beyond the keys' range.
bool buildGrid(const PointCloud& in, const std::vector<std::uint32_t>& finite, double h,
               PointGrid& g) {
  g.h = h, g.inv_h = 1.0 / h;
  const std::uint32_t f0 = finite.front();
  g.ox = in.x[f0], g.oy = in.y[f0], g.oz = in.z[f0];
  g.map = detail::CellMap(finite.size() / 4 + 64);
  g.cell_xyz.clear();
  std::vector<std::uint32_t> count, cell_of(finite.size());
  for (std::size_t f = 0; f < finite.size(); ++f) {
    const std::uint32_t i = finite[f];
    std::int64_t k[3];
    cellOf(in, i, f0, g.inv_h, k);
    if (!detail::keyFits(k[0], k[1], k[2])) return false;
    bool inserted = false;
    const std::uint32_t c = g.map.findOrInsert(detail::packKey(k[0], k[1], k[2]), inserted);
    if (inserted) {
      g.cell_xyz.insert(g.cell_xyz.end(),
                        {static_cast<std::int32_t>(k[0]), static_cast<std::int32_t>(k[1]),
                         static_cast<std::int32_t>(k[2])});
      count.push_back(0);
    }
    ++count[c];
    cell_of[f] = c;
  }
  const std::size_t n_cells = count.size();
  g.start.assign(n_cells + 1, 0);
  for (std::size_t c = 0; c < n_cells; ++c) g.start[c + 1] = g.start[c] + count[c];
  std::vector<std::uint32_t> fill(g.start.begin(), g.start.end() - 1);
  g.x.resize(finite.size()), g.y.resize(finite.size()), g.z.resize(finite.size());
  g.index.resize(finite.size());
  for (std::size_t f = 0; f < finite.size(); ++f) {
    const std::uint32_t i = finite[f];
    const std::uint32_t j = fill[cell_of[f]]++;
    g.x[j] = in.x[i] - g.ox, g.y[j] = in.y[i] - g.oy, g.z[j] = in.z[i] - g.oz;
    g.index[j] = i;
  }
  return true;
}

// Squared distances from (qx, qy, qz) to the n points (x, y, z)[j], into out.
UPD_VECTOR_CLONES
void distances2(const float* __restrict x, const float* __restrict y, const float* __restrict z,
                std::size_t n, float qx, float qy, float qz, float* __restrict out) {
  for (std::size_t j = 0; j < n; ++j) {
    const float dx = x[j] - qx, dy = y[j] - qy, dz = z[j] - qz;
    out[j] = dx * dx + dy * dy + dz * dz;
  }
}

// Mean of the square roots of d2[1, n): the k nearest's mean distance, leaving out the first
// (the query point itself, or a duplicate of it at the same distance 0: the k-d tree's answer,
// whichever of the two it lists first).
double meanRootWithoutFirst(const float* d2, std::size_t n) {
  double s = 0;
  for (std::size_t j = 1; j < n; ++j) s += std::sqrt(static_cast<double>(d2[j]));
  return s / static_cast<double>(n - 1);
}

// The k smallest squared distances seen so far, ascending (k <= kMax: the outlier filter's k
// is a few dozen at most; with a larger one the caller asks the k-d tree instead).
class NearestK {
 public:
  static constexpr std::size_t kMax = 128;
  explicit NearestK(std::size_t k) : k_(k) {}
  void clear() { n_ = 0; }
  void offer(float d2) {
    if (n_ == k_) {
      if (!(d2 < d_[n_ - 1])) return;
    } else {
      ++n_;
    }
    std::size_t pos = n_ - 1;
    for (; pos > 0 && d2 < d_[pos - 1]; --pos) d_[pos] = d_[pos - 1];
    d_[pos] = d2;
  }
  bool full() const { return n_ == k_; }
  float worst() const { return d_[n_ - 1]; }
  double meanWithoutFirst() const { return meanRootWithoutFirst(d_, n_); }

 private:
  std::size_t k_, n_ = 0;
  float d_[kMax];
};

// The points of a block of cells as one structure of arrays, padded to a multiple of 16 with
// far-away points (their distances are huge and never kept).
struct BlockPoints {
  std::vector<float> x, y, z;
  std::size_t n = 0;
  void fill(const PointGrid& g, const std::vector<std::uint32_t>& cells) {
    n = 0;
    for (const std::uint32_t c : cells) n += g.start[c + 1] - g.start[c];
    const std::size_t cap = (n + 15) / 16 * 16;
    x.assign(cap, 1e18f), y.assign(cap, 1e18f), z.assign(cap, 1e18f);
    std::size_t j = 0;
    for (const std::uint32_t c : cells) {
      const std::uint32_t b = g.start[c], e = g.start[c + 1];
      std::copy(&g.x[b], &g.x[b] + (e - b), &x[j]);
      std::copy(&g.y[b], &g.y[b] + (e - b), &y[j]);
      std::copy(&g.z[b], &g.z[b] + (e - b), &z[j]);
      j += e - b;
    }
  }
};

// Distance from q (grid coordinates relative to the anchor) to the outside of the block of
// cells within Chebyshev distance ring of its cell (cx, cy, cz): no point outside that block
// is nearer.
double blockMargin(const PointGrid& g, double qx, double qy, double qz, std::int32_t cx,
                   std::int32_t cy, std::int32_t cz, int ring) {
  double m = std::numeric_limits<double>::infinity();
  const double q[3] = {qx, qy, qz};
  const std::int32_t c[3] = {cx, cy, cz};
  for (int a = 0; a < 3; ++a) {
    const double lo = static_cast<double>(c[a] - ring) * g.h;
    const double hi = static_cast<double>(c[a] + ring + 1) * g.h;
    m = std::min({m, q[a] - lo, hi - q[a]});
  }
  return m;
}

// The cell offsets at Chebyshev distance ring (0 .. 3), sorted by their distance.
const std::vector<std::array<std::int32_t, 3>>& shellOffsets(int ring) {
  static const auto table = [] {
    std::array<std::vector<std::array<std::int32_t, 3>>, 4> t;
    for (std::int32_t r = 0; r < 4; ++r) {
      for (std::int32_t dz = -r; dz <= r; ++dz) {
        for (std::int32_t dy = -r; dy <= r; ++dy) {
          for (std::int32_t dx = -r; dx <= r; ++dx) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) == r) {
              t[static_cast<std::size_t>(r)].push_back({dx, dy, dz});
            }
          }
        }
      }
      std::stable_sort(t[static_cast<std::size_t>(r)].begin(), t[static_cast<std::size_t>(r)].end(),
                       [](const auto& a, const auto& b) {
                         return a[0] * a[0] + a[1] * a[1] + a[2] * a[2] <
                                b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
                       });
    }
    return t;
  }();
  return table[static_cast<std::size_t>(ring)];
}

// How many points per occupied cell the grid aims at: the k + 1 nearest of a point on a
// surface then lie within about half a cell, inside the 3 x 3 x 3 block around its cell.
double gridCellEdge(const PointCloud& in, const std::vector<std::uint32_t>& finite, int k) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const std::uint32_t i : finite) {
    const Eigen::Vector3d p = in.point(i).cast<double>();
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  const Eigen::Vector3d ext = (hi - lo).cwiseMax(1e-3);
  // First guess: the points filling the bounding box; then one correction from the measured
  // points per occupied cell, as for a surface (count ~ h^2).
  double h = std::cbrt(ext.prod() / static_cast<double>(finite.size()));
  const std::uint32_t f0 = finite.front();
  const double inv_h = 1.0 / h;
  detail::CellMap cells(finite.size() / 4 + 64);
  for (const std::uint32_t i : finite) {
    std::int64_t c[3];
    cellOf(in, i, f0, inv_h, c);
    if (!detail::keyFits(c[0], c[1], c[2])) return h;  // (buildGrid refuses it too: k-d tree)
    bool inserted = false;
    cells.findOrInsert(detail::packKey(c[0], c[1], c[2]), inserted);
  }
  const double per_cell = static_cast<double>(finite.size()) / static_cast<double>(cells.size());
  const double target = static_cast<double>(k + 1);
  return h * std::clamp(std::sqrt(target / per_cell), 0.125, 8.0);
}

}  // namespace

std::vector<double> meanNeighbourDistances(const PointCloud& in, int k) {
  requireParam(k >= 1, "PreprocessParams", "outlier_k", k, "must be >= 1");
  std::vector<double> mean_dist(in.size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<std::uint32_t> finite;
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in.isFinite(i)) finite.push_back(static_cast<std::uint32_t>(i));
  }
  if (finite.empty()) return mean_dist;
  const std::size_t want = static_cast<std::size_t>(k) + 1;  // the point itself comes first
  // The k + 1 nearest by a grid of cells: every point of a cell is compared with the points of
  // the 27 cells around (gathered once per cell); the answer is exact where the (k + 1)-th
  // distance is within the block's margin. Where it is not (the edge of the data, a lone
  // point), the block grows ring by ring up to kMaxRing, then the k-d tree answers.
  constexpr int kMaxRing = 3;
  PointGrid g;
  std::vector<std::uint32_t> rest;  // points left to the k-d tree
  // (A k beyond NearestK's capacity, or a cloud beyond the keys' range: the k-d tree alone.)
  if (want > NearestK::kMax || !buildGrid(in, finite, gridCellEdge(in, finite, k), g)) {
    rest = finite;
  } else {
    const std::size_t n_cells = g.start.size() - 1;
#pragma omp parallel
    {
      NearestK best(want);
      std::vector<float> d2;
      std::vector<std::uint32_t> around, ring1;  // cells of a block, of the 3 x 3 x 3 block
      BlockPoints block;                         // the points of ring1, nearest cells first
      std::vector<float> bd2;
      std::vector<std::uint32_t> my_rest;
      // The cells at Chebyshev distance `ring` from (cx, cy, cz), nearest first: the nearer
      // points come first, so that NearestK rejects most later ones with one comparison.
      // Ring 0 and 1 make a cell's block (copied once per cell); the outer rings are scanned
      // only for the few points whose k-th distance the block's margin does not settle.
      const auto shell = [&](std::int32_t cx, std::int32_t cy, std::int32_t cz, int ring) {
        around.clear();
        for (const auto& d : shellOffsets(ring)) {
          const std::uint32_t c = g.find(cx + d[0], cy + d[1], cz + d[2]);
          if (c != detail::kNoIndex) around.push_back(c);
        }
      };
#pragma omp for schedule(dynamic, 16)
      for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
        const auto c = static_cast<std::size_t>(cc);
        const std::int32_t cx = g.cell_xyz[3 * c], cy = g.cell_xyz[3 * c + 1],
                           cz = g.cell_xyz[3 * c + 2];
        shell(cx, cy, cz, 0);
        ring1 = around;
        shell(cx, cy, cz, 1);
        ring1.insert(ring1.end(), around.begin(), around.end());
        block.fill(g, ring1);
        bd2.resize(block.x.size());
        for (std::uint32_t q = g.start[c]; q < g.start[c + 1]; ++q) {
          const float qx = g.x[q], qy = g.y[q], qz = g.z[q];
          best.clear();
          // The 3 x 3 x 3 block: its distances in one vector pass, then the nearest kept.
          distances2(block.x.data(), block.y.data(), block.z.data(), block.x.size(), qx, qy, qz,
                     bd2.data());
          for (std::size_t j = 0; j < block.n; ++j) best.offer(bd2[j]);
          int ring = 1;
          while (true) {
            const double margin = blockMargin(g, qx, qy, qz, cx, cy, cz, ring);
            if (best.full() && static_cast<double>(best.worst()) <= margin * margin) break;
            if (++ring > kMaxRing) break;
            shell(cx, cy, cz, ring);
            for (const std::uint32_t b : around) {
              // A cell whose box lies beyond the k-th distance so far holds none of the k.
              if (best.full() && g.boxDistance2(b, qx, qy, qz) > best.worst()) continue;
              const std::size_t n = g.start[b + 1] - g.start[b];
              d2.resize(std::max(d2.size(), n));
              distances2(&g.x[g.start[b]], &g.y[g.start[b]], &g.z[g.start[b]], n, qx, qy, qz,
                         d2.data());
              for (std::size_t j = 0; j < n; ++j) best.offer(d2[j]);
            }
          }
          if (ring > kMaxRing) {
            my_rest.push_back(g.index[q]);
            continue;
          }
          mean_dist[g.index[q]] = best.meanWithoutFirst();
        }
      }
#pragma omp critical(upd_outlier_rest)
      rest.insert(rest.end(), my_rest.begin(), my_rest.end());
    }
  }
  if (!rest.empty()) {
    // (The order of rest depends on the threads; each point's answer does not.)
    const KdTree tree(in);
#pragma omp parallel
    {
      std::vector<std::uint32_t> nb;
      std::vector<float> d2;
#pragma omp for schedule(dynamic, 64)
      for (std::ptrdiff_t r = 0; r < static_cast<std::ptrdiff_t>(rest.size()); ++r) {
        const std::uint32_t i = rest[static_cast<std::size_t>(r)];
        tree.knnSearch(in.point(i), k + 1, nb, &d2);
        if (nb.size() < 2) continue;
        mean_dist[i] = meanRootWithoutFirst(d2.data(), d2.size());
      }
    }
  }
  return mean_dist;
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

}  // namespace upd
