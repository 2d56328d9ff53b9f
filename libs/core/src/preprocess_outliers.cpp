// The statistical outlier filter's neighbour search, meanNeighbourDistances: the mean distance
// of every point to its k nearest, by a grid of cells (CellGrid) where that settles them, by
// comparing with every point for the few left, and by the k-d tree when many are left.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include "fast_cell_map.h"
#include "fast_simd.h"
#include "upd/core/kdtree.h"
#include "upd/core/preprocess.h"

namespace upd::core {

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
// the fast UPD's lattice): cell ids from the CellGrid, and the points' coordinates relative
// to the anchor sorted by cell (counting sort), with their cloud indices.
struct PointGrid {
  double h = 1, inv_h = 1;
  float ox = 0, oy = 0, oz = 0;  // anchor
  detail::CellGrid cells;
  std::vector<std::uint32_t> start;  // n_cells + 1
  std::vector<float> x, y, z;        // by cell
  std::vector<std::uint32_t> index;  // by cell: the cloud's index

  // Squared distance from (qx, qy, qz) to the box of cell c (0 inside).
  float boxDistance2(std::uint32_t c, float qx, float qy, float qz) const {
    const float q[3] = {qx, qy, qz};
    float d2 = 0.f;
    for (int a = 0; a < 3; ++a) {
      const auto lo = static_cast<float>(cells.xyz(c)[a] * h);
      const auto hi = static_cast<float>((cells.xyz(c)[a] + 1) * h);
      const float d = q[a] < lo ? lo - q[a] : (q[a] > hi ? q[a] - hi : 0.f);
      d2 += d * d;
    }
    // (Shrunk by a rounding margin: a cell is skipped only when it is certainly farther.)
    return d2 * (1.f - 1e-5f);
  }
  std::uint32_t find(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
    return cells.find(cx, cy, cz);
  }
};

// Bins the finite points at edge h; false when a point lies beyond the keys' range.
bool buildGrid(const PointCloud& in, const std::vector<std::uint32_t>& finite, double h,
               PointGrid& g) {
  g.h = h, g.inv_h = 1.0 / h;
  const std::uint32_t f0 = finite.front();
  g.ox = in.x[f0], g.oy = in.y[f0], g.oz = in.z[f0];
  g.cells = detail::CellGrid(finite.size() / 4 + 64);
  std::vector<std::uint32_t> cell_of(finite.size());
  const auto coords = [&](std::size_t f, std::int64_t(&c)[3]) {
    cellOf(in, finite[f], f0, g.inv_h, c);
    return true;
  };
  if (!detail::binCells(0, finite.size(), coords, g.cells, cell_of.data())) return false;
  detail::CellLists by_cell;
  detail::listByCell(
      finite.size(), g.cells.size(), [&](std::size_t f) { return cell_of[f]; }, by_cell);
  g.start = std::move(by_cell.start);
  g.x.resize(finite.size()), g.y.resize(finite.size()), g.z.resize(finite.size());
  g.index.resize(finite.size());
  for (std::size_t j = 0; j < finite.size(); ++j) {
    const std::uint32_t i = finite[by_cell.order[j]];
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
  std::size_t size() const { return n_; }
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

// The cell edge: about (k + 1) / 3 points per occupied cell. On a surface the k + 1 nearest of a
// point then lie within about a cell's edge, mostly inside the 3 x 3 x 3 block around its cell,
// which holds ~80 points (cells of k + 1 points made blocks of ~210, each compared with every
// point of the cell: 1.4 times the instructions on a voxelized Kinect frame).
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
  detail::CellMap cells(finite.size() / 4 + 64);  // (counted only: no cell ids kept)
  for (const std::uint32_t i : finite) {
    std::int64_t c[3];
    cellOf(in, i, f0, inv_h, c);
    if (!detail::keyFits(c[0], c[1], c[2])) return h;  // (buildGrid refuses it too: k-d tree)
    bool inserted = false;
    cells.findOrInsert(detail::packKey(c[0], c[1], c[2]), inserted);
  }
  const double per_cell = static_cast<double>(finite.size()) / static_cast<double>(cells.size());
  const double target = static_cast<double>(k + 1) / 3.0;
  return h * std::clamp(std::sqrt(target / per_cell), 0.125, 8.0);
}

// The k + 1 nearest of every point by the grid g, their mean distance into mean_dist: every
// point of a cell is compared with the points of the 27 cells around (gathered once per cell);
// the answer is exact where the (k + 1)-th distance is within the block's margin. Where it is
// not (the edge of the data, a lone point), the block grows ring by ring up to kMaxRing (each
// ring looked up once per cell); the points still unsettled go to rest (their grid positions).
void gridMeanDistances(const PointGrid& g, std::size_t want, std::vector<double>& mean_dist,
                       std::vector<std::uint32_t>& rest) {
  constexpr int kMaxRing = 3;
  const std::size_t n_cells = g.start.size() - 1;
#pragma omp parallel
  {
    NearestK best(want);
    std::vector<float> d2;
    std::vector<std::uint32_t> around, ring1;  // cells of a block, of the 3 x 3 x 3 block
    BlockPoints block;                         // the points of ring1, nearest cells first
    std::vector<float> bd2;
    std::vector<std::uint32_t> my_rest;
    std::vector<std::uint32_t> outer[kMaxRing + 1];  // the current cell's outer rings, as needed
    // The cells at Chebyshev distance `ring` from (cx, cy, cz), nearest first: the nearer
    // points come first, so that NearestK rejects most later ones with one comparison. Ring 0
    // and 1 make a cell's block (copied once per cell); the outer rings are scanned only for
    // the few points whose k-th distance the block's margin does not settle.
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
      const std::int32_t cx = g.cells.xyz(c)[0], cy = g.cells.xyz(c)[1], cz = g.cells.xyz(c)[2];
      shell(cx, cy, cz, 0);
      ring1 = around;
      shell(cx, cy, cz, 1);
      ring1.insert(ring1.end(), around.begin(), around.end());
      block.fill(g, ring1);
      bd2.resize(block.x.size());
      int outer_done = 1;  // outer[2 .. outer_done] hold this cell's rings
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
          if (ring > outer_done) {  // (looked up once per cell, for its first point needing it)
            shell(cx, cy, cz, ring);
            outer[ring].swap(around);
            outer_done = ring;
          }
          for (const std::uint32_t b : outer[ring]) {
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
          my_rest.push_back(q);
          continue;
        }
        mean_dist[g.index[q]] = best.meanWithoutFirst();
      }
    }
#pragma omp critical(upd_outlier_rest)
    rest.insert(rest.end(), my_rest.begin(), my_rest.end());
  }
}

// The mean distances of the few grid points at positions todo, each compared with every point
// of the grid (cheaper than building a k-d tree for a few dozen).
void allPairsMeanDistances(const PointGrid& g, std::size_t want,
                           const std::vector<std::uint32_t>& todo, std::vector<double>& mean_dist) {
  const std::size_t n = g.x.size();
#pragma omp parallel if (todo.size() > 1)
  {
    NearestK best(want);
    std::vector<float> d2(n);
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t r = 0; r < static_cast<std::ptrdiff_t>(todo.size()); ++r) {
      const std::uint32_t q = todo[static_cast<std::size_t>(r)];
      distances2(g.x.data(), g.y.data(), g.z.data(), n, g.x[q], g.y[q], g.z[q], d2.data());
      best.clear();
      for (std::size_t j = 0; j < n; ++j) best.offer(d2[j]);
      if (best.size() >= 2) mean_dist[g.index[q]] = best.meanWithoutFirst();
    }
  }
}

// The mean distances of the points `todo` by the k-d tree.
void kdTreeMeanDistances(const PointCloud& in, int k, const std::vector<std::uint32_t>& todo,
                         std::vector<double>& mean_dist) {
  // (The order of todo depends on the threads; each point's answer does not.)
  const KdTree tree(in);
#pragma omp parallel
  {
    std::vector<std::uint32_t> nb;
    std::vector<float> d2;
#pragma omp for schedule(dynamic, 64)
    for (std::ptrdiff_t r = 0; r < static_cast<std::ptrdiff_t>(todo.size()); ++r) {
      const std::uint32_t i = todo[static_cast<std::size_t>(r)];
      tree.knnSearch(in.point(i), k + 1, nb, &d2);
      if (nb.size() < 2) continue;
      mean_dist[i] = meanRootWithoutFirst(d2.data(), d2.size());
    }
  }
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
  PointGrid g;
  // (A k beyond NearestK's capacity, or a cloud beyond the keys' range: the k-d tree alone.)
  if (want > NearestK::kMax || !buildGrid(in, finite, gridCellEdge(in, finite, k), g)) {
    kdTreeMeanDistances(in, k, finite, mean_dist);
    return mean_dist;
  }
  std::vector<std::uint32_t> rest;  // grid positions of the points the rings did not settle
  gridMeanDistances(g, want, mean_dist, rest);
  // A few left (lone points, tiny clouds): compared with every point; many: the k-d tree.
  constexpr std::size_t kMaxAllPairs = 128;
  if (rest.size() <= kMaxAllPairs) {
    allPairsMeanDistances(g, want, rest, mean_dist);
  } else {
    for (std::uint32_t& q : rest) q = g.index[q];
    kdTreeMeanDistances(in, k, rest, mean_dist);
  }
  return mean_dist;
}

}  // namespace upd::core
