// The statistical outlier filter's neighbour search, meanNeighbourDistances: the mean distance
// of every point to its k nearest, by a grid of cells (PointGrid: its cells found in a dense
// table over their box, or by the hash where that box is sparse) where that settles them, by
// comparing with every point for the few left, and by the k-d tree when many are left.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <vector>

#include "fast_cell_map.h"
#include "fast_cell_ranks.h"
#include "fast_simd.h"
#include "upd/core/kdtree.h"
#include "upd/core/preprocess.h"
#include "upd/core/vector_clones.h"

#include "preprocess_internal.h"

namespace upd::core {

namespace {

// Coordinates of the padding: their distances are huge and never kept.
constexpr float kFarPoint = 1e18f;
// The slack of the rows for copyRunByEights.
constexpr std::size_t kCopyLanes = 8;

// The finite points binned into cubic cells of edge h (anchored at the first finite point, as
// the fast UPD's lattice): cell ids from the CellGrid, and the points' coordinates relative
// to the anchor sorted by cell (counting sort), with their cloud indices.
struct PointGrid {
  double h = 1, inv_h = 1;
  float ox = 0, oy = 0, oz = 0;  // anchor
  detail::CellGrid cells;
  std::vector<std::uint32_t> start;  // n_cells + 1
  std::uint32_t max_cell_points = 0;  // the most points in a cell
  std::vector<float> x, y, z;        // by cell (then kCopyLanes of slack)
  std::vector<std::uint32_t> index;  // by cell: the cloud's index
  std::vector<std::uint32_t> cell_of;  // (buildGrid's buffers)
  detail::CellLists by_cell;
  detail::CellCoords coords;

  // Squared distance from (qx, qy, qz) to the box of cell c (0 inside).
  float boxDistance2(std::uint32_t c, float qx, float qy, float qz) const {
    const float q[3] = {qx, qy, qz};
    float d2 = 0.f;
    for (int a = 0; a < 3; ++a) {
      const auto lo = static_cast<float>(xyz(c)[a] * h);
      const auto hi = static_cast<float>((xyz(c)[a] + 1) * h);
      const float d = q[a] < lo ? lo - q[a] : (q[a] > hi ? q[a] - hi : 0.f);
      d2 += d * d;
    }
    // (Shrunk by a rounding margin: a cell is skipped only when it is certainly farther.)
    return d2 * (1.f - 1e-5f);
  }
  std::uint32_t find(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
    return cells.find(cx, cy, cz);
  }

  // The occupied cells by rank over their box widened by kDenseMargin cells on every side, and
  // the shells' cell offsets in it, nearest first: a shell's cells by a load and a population
  // count each instead of a hash look-up. Off (has_dense false) where the table declines the
  // box.
  static constexpr int kDenseMargin = 3;
  bool has_dense = false;
  detail::RankedCells dense;
  detail::TeamCellCounts team_counts;  // (listByCellTeam's)
  std::array<std::vector<std::int64_t>, 4> dense_offsets;  // by ring (0 .. 3)
  // The cells' coordinates, 3 per cell in id order (the ids by rank in the box, or where the
  // table is off in order of first sight, as the hash's CellGrid numbers them).
  std::vector<std::int32_t> cell_xyz;
  std::size_t n_cells = 0;
  const std::int32_t* xyz(std::size_t c) const { return &cell_xyz[3 * c]; }
};

// The cells' rank table (nothing marked) and its shells' offsets over the box [lo, hi] widened
// by kDenseMargin; false (has_dense off) where the table declines the box.
const std::vector<std::array<std::int32_t, 3>>& shellOffsets(int ring);
bool makeDense(PointGrid& g, const std::int32_t (&lo)[3], const std::int32_t (&hi)[3],
               std::size_t n_points) {
  g.has_dense = g.dense.reset(lo, hi, PointGrid::kDenseMargin, n_points);
  if (!g.has_dense) return false;
  for (int ring = 0; ring <= PointGrid::kDenseMargin; ++ring) {
    std::vector<std::int64_t>& o = g.dense_offsets[static_cast<std::size_t>(ring)];
    o.clear();
    for (const auto& d : shellOffsets(ring)) o.push_back(g.dense.offset(d[0], d[1], d[2]));
  }
  return true;
}

// Grid points [j0, j1) (cloud points of the cells in id order) copied from the cloud, relative to
// the anchor, with their cloud indices.
void copyByCell(const PointCloud& in, const std::vector<std::uint32_t>& finite, PointGrid& g,
                std::size_t j0, std::size_t j1) {
  for (std::size_t j = j0; j < j1; ++j) {
    const std::uint32_t i = finite[g.by_cell.order[j]];
    g.x[j] = in.x[i] - g.ox, g.y[j] = in.y[i] - g.oy, g.z[j] = in.z[i] - g.oz;
    g.index[j] = i;
  }
}

// The grid's start, the most points in a cell and its point rows sized (kCopyLanes of slack:
// BlockPoints::fill copies 8 at a time), once the points are listed by cell.
void sizeRows(PointGrid& g, std::size_t n_finite) {
  g.start.assign(g.by_cell.start.begin(), g.by_cell.start.end());
  g.max_cell_points = g.by_cell.mostInACell();
  const std::size_t rows = n_finite + kCopyLanes;
  g.x.resize(rows), g.y.resize(rows), g.z.resize(rows);
  for (std::size_t j = n_finite; j < rows; ++j) g.x[j] = g.y[j] = g.z[j] = kFarPoint;
  g.index.resize(n_finite);
}

// The ids of the cells of points [b, e) (their coordinates in k) into cell_of. (Cloned: on
// x86-64-v3 and up GCC makes countBits one POPCNT.)
UPD_VECTOR_CLONES
void rankedIds(const detail::RankedCells& ranks, const detail::CellCoords& k, std::size_t b,
               std::size_t e, std::uint32_t* cell_of) {
  for (std::size_t f = b; f < e; ++f) cell_of[f] = ranks.id(ranks.index(k.x[f], k.y[f], k.z[f]));
}

// Where the grid's cells are numbered by rank: the cells marked, the points listed by cell and
// copied, on the team from kTeamPoints points (the same grid on any number of threads).
void rankAndCopy(const PointCloud& in, const std::vector<std::uint32_t>& finite, PointGrid& g) {
  constexpr std::size_t kTeamPoints = 16384;
  const std::size_t n = finite.size();
  std::vector<std::uint32_t>& cell_of = g.cell_of;
  const detail::CellCoords& k = g.coords;
  const auto index = [&](std::size_t f) { return g.dense.index(k.x[f], k.y[f], k.z[f]); };
#pragma omp parallel if (n >= kTeamPoints)
  {
    g.dense.buildTeam(n, index);
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    rankedIds(g.dense, k, detail::RankedCells::share(n, team, me),
              detail::RankedCells::share(n, team, me + 1), cell_of.data());
#pragma omp barrier
    detail::listByCellTeam(
        n, g.dense.size(), [&](std::size_t f) { return cell_of[f]; }, g.by_cell, g.team_counts);
#pragma omp single
    {
      g.n_cells = g.dense.size();
      g.cell_xyz.resize(3 * g.n_cells);
      sizeRows(g, n);
    }
#pragma omp for schedule(static) nowait
    for (std::size_t c = 0; c < g.n_cells; ++c) {
      const std::uint32_t f = g.by_cell.order[g.start[c]];
      g.cell_xyz[3 * c] = k.x[f], g.cell_xyz[3 * c + 1] = k.y[f], g.cell_xyz[3 * c + 2] = k.z[f];
    }
    copyByCell(in, finite, g, detail::RankedCells::share(n, team, me),
               detail::RankedCells::share(n, team, me + 1));
  }
}

// Bins the finite points at edge h; false when a point lies beyond the keys' range.
bool buildGrid(const PointCloud& in, const std::vector<std::uint32_t>& finite, double h,
               PointGrid& g) {
  g.h = h, g.inv_h = 1.0 / h;
  const std::uint32_t f0 = finite.front();
  g.ox = in.x[f0], g.oy = in.y[f0], g.oz = in.z[f0];
  std::vector<std::uint32_t>& cell_of = g.cell_of;
  cell_of.resize(finite.size());
  g.coords.compute(in, finite, g.inv_h);
  std::int32_t lo[3], hi[3];
  g.coords.box(lo, hi);
  if (!detail::keyFits(lo[0], lo[1], lo[2]) || !detail::keyFits(hi[0], hi[1], hi[2])) return false;
  if (makeDense(g, lo, hi, finite.size())) {
    rankAndCopy(in, finite, g);
    return true;
  }
  g.cells.clear(finite.size() / 4 + 64);
  const auto coords = [&](std::size_t f, std::int64_t(&c)[3]) {
    c[0] = g.coords.x[f], c[1] = g.coords.y[f], c[2] = g.coords.z[f];
    return true;
  };
  detail::binCells(0, finite.size(), coords, g.cells, cell_of.data());  // (every cell fits)
  g.cell_xyz.assign(g.cells.coords().begin(), g.cells.coords().end());
  g.n_cells = g.cells.size();
  detail::listByCell(
      finite.size(), g.n_cells, [&](std::size_t f) { return cell_of[f]; }, g.by_cell);
  sizeRows(g, finite.size());
  copyByCell(in, finite, g, 0, finite.size());
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

// The points of a block of cells as one structure of arrays, padded to a multiple of 8 (cap,
// gatherWithin's vectors) with far-away points.
struct BlockPoints {
  std::vector<float> x, y, z;
  std::size_t n = 0, cap = 0;
  void fill(const PointGrid& g, const std::vector<std::uint32_t>& cells) {
    // (Room for the fullest cell's points in every cell, at most the grid, and the slack: no
    // count of the block's points before the copy.)
    const std::size_t room =
        std::min(g.index.size(), cells.size() * std::size_t{g.max_cell_points}) + 2 * kCopyLanes;
    if (x.size() < room) x.resize(room), y.resize(room), z.resize(room);
    float *bx = x.data(), *by = y.data(), *bz = z.data();
    std::size_t j = 0;
    for (const std::uint32_t c : cells) {
      const std::uint32_t b = g.start[c], e = g.start[c + 1];
      detail::copyRunByEights(g.x.data(), g.y.data(), g.z.data(), b, e, bx + j, by + j, bz + j);
      j += e - b;
    }
    n = j;
    cap = (n + 7) / 8 * 8;
    // (Every point of the vectors written: the padding, 8 from n, in the slack.)
    detail::fillEight(kFarPoint, bx + n, by + n, bz + n);
  }
};

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

// The occupied cells at the offsets of a shell around the cell at index at of the rank table,
// in the offsets' order, appended to out. (Cloned, as rankedIds.)
UPD_VECTOR_CLONES
void rankedShell(const detail::RankedCells& ranks, std::size_t at,
                 const std::vector<std::int64_t>& offsets, std::vector<std::uint32_t>& out) {
  for (const std::int64_t o : offsets) {
    const std::uint32_t c = ranks.id(at + static_cast<std::size_t>(o));
    if (c != detail::kNoIndex) out.push_back(c);
  }
}

// The cell edge: about (k + 1) / 2 points per occupied cell. On a surface the k + 1 nearest of a
// point then lie within about 0.8 of a cell's edge, inside the 3 x 3 x 3 block around its cell
// (~120 points on a voxelized Kinect frame) for all but a few per cent of the points, which look
// at the 5 x 5 x 5 block. (With (k + 1) / 3 points more points need the wider block; with
// k + 1 the blocks hold ~210 points: each 5-10 % more instructions on voxelized frames.)
double gridCellEdge(const PointCloud& in, const std::vector<std::uint32_t>& finite, int k,
                    detail::CellCoords& coords) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  const std::size_t n = finite.size();
  // (On the team from kTeamPoints: the box by min and max, the same on any number of threads.)
#pragma omp parallel for if (n > detail::CellCoords::kTeamPoints) schedule(static) \
    reduction(min : lo[:3]) reduction(max : hi[:3])
  for (std::size_t f = 0; f < n; ++f) {
    const std::uint32_t i = finite[f];
    const double p[3] = {in.x[i], in.y[i], in.z[i]};
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  }
  const Eigen::Vector3d ext =
      (Eigen::Vector3d(hi[0], hi[1], hi[2]) - Eigen::Vector3d(lo[0], lo[1], lo[2])).cwiseMax(1e-3);
  // First guess: the points filling the bounding box; then one correction from the measured
  // points per occupied cell, as for a surface (count ~ h^2).
  double h = std::cbrt(ext.prod() / static_cast<double>(finite.size()));
  coords.compute(in, finite, 1.0 / h);
  std::int32_t c_lo[3], c_hi[3];
  coords.box(c_lo, c_hi);
  if (!detail::keyFits(c_lo[0], c_lo[1], c_lo[2]) || !detail::keyFits(c_hi[0], c_hi[1], c_hi[2])) {
    return h;  // (buildGrid refuses it too: k-d tree)
  }
  const double per_cell =
      static_cast<double>(finite.size()) / static_cast<double>(coords.countCells(c_lo, c_hi));
  const double target = static_cast<double>(k + 1) / 2.0;
  return h * std::clamp(std::sqrt(target / per_cell), 0.125, 8.0);
}

// The searches of one thread, cell by cell: the points of a cell share their blocks (the cells
// within Chebyshev distance 1, and 2 when the first does not settle a point's k nearest),
// gathered once per cell, nearest cells first.
class CellSearch {
 public:
  // A search of grid g for the want nearest (the buffers kept from the last call).
  void start(const PointGrid& g, std::size_t want) {
    g_ = &g, want_ = want, best_ = NearestK(want);
    kth_ = std::numeric_limits<float>::infinity();
  }

  void startCell(std::size_t c) {
    cx_ = g_->xyz(c)[0], cy_ = g_->xyz(c)[1], cz_ = g_->xyz(c)[2];
    for (int ring = 1; ring <= 3; ++ring) {
      for (int a = 0; a < 3; ++a) {
        lo_[ring][a] = static_cast<double>(g_->xyz(c)[a] - ring) * g_->h;
        hi_[ring][a] = static_cast<double>(g_->xyz(c)[a] + ring + 1) * g_->h;
      }
    }
    cells_.clear();
    built_ = -1;
    grow(1);
  }

  // The mean distance of grid point q (of the current cell) to its k nearest, or NaN when they
  // lie beyond 3 rings (a lone point, a tiny cloud).
  double meanOf(std::uint32_t q) {
    const float qx = g_->x[q], qy = g_->y[q], qz = g_->z[q];
    for (int ring = 1; ring <= 2; ++ring) {
      if (built_ < ring) grow(ring);
      const BlockPoints& b = block_[ring];
      const double m = margin(qx, qy, qz, ring);
      const auto m2 = static_cast<float>(m * m * (1 - 1e-6));
      // The previous point's k-th distance, a little widened, mostly bounds this one's: fewer
      // candidates to select from. Where it does not, the block's margin.
      const float t = std::min(m2, kth_ * kTighten);
      std::size_t c = detail::gatherWithin(b.x.data(), b.y.data(), b.z.data(), b.cap, qx, qy,
                                           qz, t, cand_.data());
      if (c < want_ && t < m2) {
        c = detail::gatherWithin(b.x.data(), b.y.data(), b.z.data(), b.cap, qx, qy, qz, m2,
                                 cand_.data());
      }
      if (c >= want_) return detail::selectMean(cand_.data(), c, want_, kth_);
    }
    // The third ring, cell by cell: a cell whose box lies beyond the k-th distance so far holds
    // none of the k.
    best_.clear();
    bd2_.resize(std::max(bd2_.size(), block_[2].n));
    distances2(block_[2].x.data(), block_[2].y.data(), block_[2].z.data(), block_[2].n, qx, qy,
               qz, bd2_.data());
    for (std::size_t j = 0; j < block_[2].n; ++j) best_.offer(bd2_[j]);
    if (built_ < 3) shell(3, ring3_), built_ = 3;
    for (const std::uint32_t b : ring3_) {
      if (best_.full() && g_->boxDistance2(b, qx, qy, qz) > best_.worst()) continue;
      const std::size_t n = g_->start[b + 1] - g_->start[b];
      d2_.resize(std::max(d2_.size(), n));
      distances2(&g_->x[g_->start[b]], &g_->y[g_->start[b]], &g_->z[g_->start[b]], n, qx, qy, qz,
                 d2_.data());
      for (std::size_t j = 0; j < n; ++j) best_.offer(d2_[j]);
    }
    const double m = margin(qx, qy, qz, 3);
    if (best_.full() && static_cast<double>(best_.worst()) <= m * m) {
      return best_.meanWithoutFirst();
    }
    return std::numeric_limits<double>::quiet_NaN();
  }

 private:
  // Distance from q (grid coordinates relative to the anchor) to the outside of the block of
  // cells within Chebyshev distance ring of the current cell: no point outside that block is
  // nearer.
  double margin(double qx, double qy, double qz, int ring) const {
    const double* lo = lo_[ring];
    const double* hi = hi_[ring];
    return std::min({qx - lo[0], hi[0] - qx, qy - lo[1], hi[1] - qy, qz - lo[2], hi[2] - qz});
  }
  // The occupied cells at Chebyshev distance ring from the current cell, nearest first, into
  // out.
  void shell(int ring, std::vector<std::uint32_t>& out) const {
    out.clear();
    if (g_->has_dense) {
      rankedShell(g_->dense, g_->dense.index(cx_, cy_, cz_),
                  g_->dense_offsets[static_cast<std::size_t>(ring)], out);
      return;
    }
    // (Away from the keys' bounds, as nearly always, the keys are the cell's plus an offset,
    // with no range test.)
    const std::int32_t xyz[3] = {cx_, cy_, cz_};
    const bool inner = detail::keyFitsAround(xyz, ring);
    const std::uint64_t key = inner ? detail::packKey(cx_, cy_, cz_) : 0;
    for (const auto& d : shellOffsets(ring)) {
      const std::uint32_t c =
          inner ? g_->cells.findKey(key + detail::keyOffset(d[0], d[1], d[2]))
                : g_->find(cx_ + d[0], cy_ + d[1], cz_ + d[2]);
      if (c != detail::kNoIndex) out.push_back(c);
    }
  }
  // The block of the cells within `ring` (1 or 2) of the current cell.
  void grow(int ring) {
    for (int r = built_ + 1; r <= ring; ++r) {
      shell(r, around_);
      cells_.insert(cells_.end(), around_.begin(), around_.end());
    }
    block_[ring].fill(*g_, cells_);
    cand_.resize(std::max(cand_.size(), block_[ring].cap));
    built_ = ring;
  }

  static constexpr float kTighten = 1.3f;  // (1.14 times the distance)
  const PointGrid* g_ = nullptr;
  std::size_t want_ = 1;
  float kth_ = std::numeric_limits<float>::infinity();  // the previous point's, squared
  NearestK best_{1};
  std::int32_t cx_ = 0, cy_ = 0, cz_ = 0;
  int built_ = -1;  // the rings gathered for the current cell
  double lo_[4][3] = {}, hi_[4][3] = {};  // the current cell's blocks' bounds by ring (1 .. 3)
  std::vector<std::uint32_t> cells_, around_, ring3_;
  BlockPoints block_[3];
  std::vector<float> bd2_, cand_, d2_;
};

// The cells [c0, c1) of grid g by search: each point's mean distance into mean_dist, the
// points not settled within 3 rings to rest. (A function of its own, kept from inlining and
// from specializing on its argument: the caller's search is a thread_local, whose address GCC
// computes again, by a call into the dynamic linker, at each use in a function that names it.)
UPD_NOIPA void searchCells(CellSearch& search, const PointGrid& g,
                           std::size_t c0, std::size_t c1,
                           std::vector<double>& mean_dist,
                           std::vector<std::uint32_t>& rest) {
  for (std::size_t c = c0; c < c1; ++c) {
    search.startCell(c);
    for (std::uint32_t q = g.start[c]; q < g.start[c + 1]; ++q) {
      const double mean = search.meanOf(q);
      if (std::isnan(mean)) {
        rest.push_back(q);
      } else {
        mean_dist[g.index[q]] = mean;
      }
    }
  }
}

// The k + 1 nearest of every point by the grid g, their mean distance into mean_dist (cells
// in dynamic shares: their cost varies); the points not settled within 3 rings go to rest
// (their grid positions).
void gridMeanDistances(const PointGrid& g, std::size_t want, std::vector<double>& mean_dist,
                       std::vector<std::uint32_t>& rest) {
  const std::size_t n_cells = g.n_cells;
  constexpr std::size_t kCellsPerShare = 16;
  const std::size_t n_shares = (n_cells + kCellsPerShare - 1) / kCellsPerShare;
#pragma omp parallel
  {
    thread_local CellSearch search;  // (its blocks' buffers kept from call to call)
    search.start(g, want);
    std::vector<std::uint32_t> my_rest;
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t sh = 0; sh < static_cast<std::ptrdiff_t>(n_shares); ++sh) {
      const std::size_t c0 = static_cast<std::size_t>(sh) * kCellsPerShare;
      searchCells(search, g, c0, std::min(n_cells, c0 + kCellsPerShare), mean_dist, my_rest);
    }
#pragma omp critical(upd_outlier_rest)
    rest.insert(rest.end(), my_rest.begin(), my_rest.end());
  }
}

// d2[0, n) offered to best. (Once it is full, a run of 16 with none below its worst, the common
// case, is passed over by one test: the worst only falls, so their offers would be refused.)
void offerAll(const float* d2, std::size_t n, NearestK& best) {
  std::size_t j = 0;
  for (; j < n && !best.full(); ++j) best.offer(d2[j]);
  constexpr std::size_t kRun = 16;
  for (; j + kRun <= n; j += kRun) {
    const float w = best.worst();
    int below = 0;
    for (std::size_t t = 0; t < kRun; ++t) below |= d2[j + t] < w ? 1 : 0;
    if (below == 0) continue;
    for (std::size_t t = 0; t < kRun; ++t) best.offer(d2[j + t]);
  }
  for (; j < n; ++j) best.offer(d2[j]);
}

// The mean distances of the few grid points at positions todo, each compared with every point
// of the grid (cheaper than building a k-d tree for a few dozen).
void allPairsMeanDistances(const PointGrid& g, std::size_t want,
                           const std::vector<std::uint32_t>& todo, std::vector<double>& mean_dist) {
  const std::size_t n = g.index.size();
#pragma omp parallel if (todo.size() > 1)
  {
    NearestK best(want);
    std::vector<float> d2(n);
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t r = 0; r < static_cast<std::ptrdiff_t>(todo.size()); ++r) {
      const std::uint32_t q = todo[static_cast<std::size_t>(r)];
      distances2(g.x.data(), g.y.data(), g.z.data(), n, g.x[q], g.y[q], g.z[q], d2.data());
      best.clear();
      offerAll(d2.data(), n, best);
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
  std::vector<double> mean_dist;
  meanNeighbourDistances(in, k, mean_dist);
  return mean_dist;
}

namespace {
// meanNeighbourDistances with the calling thread's buffers (a function of its own: see
// searchCells).
UPD_NOIPA void meanNeighbourDistances(const PointCloud& in, int k,
                                      std::vector<double>& mean_dist,
                                      std::vector<std::uint32_t>& finite,
                                      std::vector<std::uint32_t>& rest,
                                      PointGrid& g) {
  mean_dist.assign(in.size(), std::numeric_limits<double>::quiet_NaN());
  finite.clear();
  if (in.countFinite() == in.size()) {  // (as the voxel grid's centroids: by a vector scan)
    finite.resize(in.size());
    std::iota(finite.begin(), finite.end(), 0u);
  } else {
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (in.isFinite(i)) finite.push_back(static_cast<std::uint32_t>(i));
    }
  }
  if (finite.empty()) return;
  const std::size_t want = static_cast<std::size_t>(k) + 1;  // the point itself comes first
  // (A k beyond NearestK's capacity, or a cloud beyond the keys' range: the k-d tree alone.)
  if (want > NearestK::kMax || !buildGrid(in, finite, gridCellEdge(in, finite, k, g.coords), g)) {
    kdTreeMeanDistances(in, k, finite, mean_dist);
    return;
  }
  rest.clear();  // grid positions of the points the rings did not settle
  gridMeanDistances(g, want, mean_dist, rest);
  // A few left (lone points, tiny clouds): compared with every point; many: the k-d tree.
  constexpr std::size_t kMaxAllPairs = 128;
  if (rest.size() <= kMaxAllPairs) {
    allPairsMeanDistances(g, want, rest, mean_dist);
  } else {
    for (std::uint32_t& q : rest) q = g.index[q];
    kdTreeMeanDistances(in, k, rest, mean_dist);
  }
}
}  // namespace

void meanNeighbourDistances(const PointCloud& in, int k, std::vector<double>& mean_dist) {
  requireParam(k >= 1, "PreprocessParams", "outlier_k", k, "must be >= 1");
  // The calling thread's buffers, kept from call to call (no allocation in a warm frame loop).
  thread_local std::vector<std::uint32_t> finite, rest;
  thread_local PointGrid g;
  meanNeighbourDistances(in, k, mean_dist, finite, rest, g);
}

}  // namespace upd::core
