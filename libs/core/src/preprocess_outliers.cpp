// The statistical outlier filter's neighbour search, meanNeighbourDistances: the mean distance
// of every point to its k nearest, by a grid of cells (PointGrid, preprocess_outlier_grid.h:
// its cells found by rank in a table of a bit per cell over their box, or by the hash where that
// box is sparse) where that settles them, by comparing with every point for the few left, and
// by the k-d tree when many are left.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <vector>

#include "chunk_deal.h"
#include "fast_cell_map.h"
#include "fast_cell_ranks.h"
#include "fast_simd.h"
#include "upd/core/kdtree.h"
#include "upd/core/preprocess.h"
#include "upd/core/vector_clones.h"

#include "preprocess_internal.h"
#include "preprocess_outlier_grid.h"

namespace upd::core {

namespace {

using detail::kCopyLanes;
using detail::kFarPoint;
using detail::PointGrid;
using detail::shellOffsets;

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

// The occupied cells at the offsets of a shell around the cell at index at of the rank table,
// in the offsets' order, appended to out. (Cloned, as rankedIds.)
UPD_VECTOR_CLONES
void rankedShell(const detail::RankedCells& ranks, std::size_t at,
                 const std::vector<std::int64_t>& offsets, std::vector<std::uint32_t>& out) {
  const std::size_t before = out.size();
  out.resize(before + offsets.size());
  out.resize(before + ranks.occupiedIds(at, offsets.data(), offsets.size(), out.data() + before));
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

  // meanOf of grid points q0 and q1 (of the current cell): where the first ring settles both
  // with at most 32 candidates each, their selections by the sorting networks at once (on
  // AVX-512: selectsSorted); else each point its own selection, or meanOf where the first ring
  // does not settle it.
  void meanOfTwo(std::uint32_t q0, std::uint32_t q1, double& mean0, double& mean1) {
    const std::uint32_t q[2] = {q0, q1};  // (startCell built the first ring's block)
    float* const cand[2] = {cand_.data(), cand2_.data()};
    std::size_t c[2];
    for (int i = 0; i < 2; ++i) {
      c[i] = gather(q[i], 1, cand[i]);
      // (Beyond the networks' 32 lanes: first narrowed near the previous point's k-th.)
      if (c[i] > 32) c[i] = detail::narrowCandidates(cand[i], c[i], want_, kth_);
    }
    if (c[0] >= want_ && c[1] >= want_ && c[0] <= 32 && c[1] <= 32) {
      float kth0 = 0.f;
      detail::selectMeansSorted(cand[0], c[0], cand[1], c[1], want_, kth0, kth_, mean0, mean1);
      return;
    }
    // (meanOf may grow the buffers: the second point's candidates are found again by data().)
    mean0 = c[0] >= want_ ? detail::selectMean(cand_.data(), c[0], want_, kth_) : meanOf(q0);
    mean1 = c[1] >= want_ ? detail::selectMean(cand2_.data(), c[1], want_, kth_) : meanOf(q1);
  }

  // The mean distance of grid point q (of the current cell) to its k nearest, or NaN when they
  // lie beyond 3 rings (a lone point, a tiny cloud).
  double meanOf(std::uint32_t q) {
    const float qx = g_->x[q], qy = g_->y[q], qz = g_->z[q];
    for (int ring = 1; ring <= 2; ++ring) {
      if (built_ < ring) grow(ring);
      const std::size_t c = gather(q, ring, cand_.data());
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
    cand2_.resize(std::max(cand2_.size(), block_[ring].cap));
    built_ = ring;
  }

  // The squared distances from grid point q to the points of the block of `ring` (built)
  // within a bound, into cand; returns their number. The previous point's k-th distance, a
  // little widened, mostly bounds this one's: fewer candidates to select from. Where it does
  // not, the block's margin (no point outside the block is nearer).
  std::size_t gather(std::uint32_t q, int ring, float* cand) const {
    const float qx = g_->x[q], qy = g_->y[q], qz = g_->z[q];
    const BlockPoints& b = block_[ring];
    const double m = margin(qx, qy, qz, ring);
    const auto m2 = static_cast<float>(m * m * (1 - 1e-6));
    const float t = std::min(m2, kth_ * kTighten);
    std::size_t c = detail::gatherWithin(b.x.data(), b.y.data(), b.z.data(), b.cap, qx, qy, qz,
                                         t, cand);
    if (c < want_ && t < m2) {
      c = detail::gatherWithin(b.x.data(), b.y.data(), b.z.data(), b.cap, qx, qy, qz, m2, cand);
    }
    return c;
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
  std::vector<float> bd2_, cand_, cand2_, d2_;  // (cand2_: meanOfTwo's second point)
};

// The cells [c0, c1) of grid g by search: each point's mean distance into mean_dist, the
// points not settled within 3 rings to rest. (A function of its own, kept from inlining and
// from specializing on its argument: the caller's search is a thread_local, whose address GCC
// computes again, by a call into the dynamic linker, at each use in a function that names it.)
UPD_NOIPA void searchCells(CellSearch& search, const PointGrid& g,
                           std::size_t c0, std::size_t c1,
                           std::vector<double>& mean_dist,
                           std::vector<std::uint32_t>& rest) {
  const auto store = [&](std::uint32_t q, double mean) {
    if (std::isnan(mean)) rest.push_back(q);  // (NaN until rest has its answer)
    mean_dist[g.index[q]] = mean;
  };
  const bool two = detail::selectsSorted();
  for (std::size_t c = c0; c < c1; ++c) {
    search.startCell(c);
    std::uint32_t q = g.start[c];
    for (; two && q + 1 < g.start[c + 1]; q += 2) {
      double mean0, mean1;
      search.meanOfTwo(q, q + 1, mean0, mean1);
      store(q, mean0), store(q + 1, mean1);
    }
    for (; q < g.start[c + 1]; ++q) store(q, search.meanOf(q));
  }
}

// The k + 1 nearest of every point by the grid g, their mean distance into mean_dist (cells
// dealt in shares by ChunkDeal: their cost varies); the points not settled within 3 rings go to
// rest (their grid positions).
void gridMeanDistances(const PointGrid& g, std::size_t want, std::vector<double>& mean_dist,
                       std::vector<std::uint32_t>& rest) {
  const std::size_t n_cells = g.n_cells;
  constexpr std::size_t kCellsPerShare = 16;
  // (Dealt by ChunkDeal: a cell's points are spread over the cloud, and their means are
  // written by point.)
  detail::ChunkDeal deal(n_cells, kCellsPerShare, openmp::maxThreads());
#pragma omp parallel
  {
    thread_local CellSearch search;  // (its blocks' buffers kept from call to call)
    search.start(g, want);
    std::vector<std::uint32_t> my_rest;
    detail::ChunkDeal::Hand hand(deal, openmp::threadIndex());
    for (std::size_t c0, c1; hand.next(c0, c1);) searchCells(search, g, c0, c1, mean_dist, my_rest);
#pragma omp critical(upd_outlier_rest)
    rest.insert(rest.end(), my_rest.begin(), my_rest.end());
  }
}

// The least of each block of kLeastBlock values of d2[0, n) into mins (the n % kLeastBlock last
// values left out). (Sixteen running minima in lanes, then theirs: cloned for the vector units.)
constexpr std::size_t kLeastBlock = 64;
UPD_VECTOR_CLONES
void blockLeasts(const float* __restrict d2, std::size_t n, float* __restrict mins) {
  constexpr std::size_t kLanes = 16;
  for (std::size_t b = 0; b < n / kLeastBlock; ++b) {
    const float* v = d2 + b * kLeastBlock;
    float m[kLanes];
    for (std::size_t t = 0; t < kLanes; ++t) m[t] = v[t];
    for (std::size_t j = kLanes; j < kLeastBlock; j += kLanes) {
      for (std::size_t t = 0; t < kLanes; ++t) m[t] = v[j + t] < m[t] ? v[j + t] : m[t];
    }
    float least = m[0];
    for (std::size_t t = 1; t < kLanes; ++t) least = m[t] < least ? m[t] : least;
    mins[b] = least;
  }
}

// The k = best's capacity smallest of d2[0, n) offered to best, and few of the others: each
// block of kLeastBlock holds its least, so the k-th least of the blocks' leasts bounds the k-th
// of all (k blocks hold a value at or below it); only the blocks that hold a value at or below it
// are offered. (Offering every value, in the grid's order, the far points first fill best and
// most later ones displace one: an insertion each.) mins, order: scratch.
void offerLeast(const float* d2, std::size_t n, std::size_t k, std::vector<float>& mins,
                std::vector<float>& order, NearestK& best) {
  // (Fewer blocks than k: no bound, every value offered.)
  const std::size_t blocks = n / kLeastBlock >= k ? n / kLeastBlock : 0;
  float bound = std::numeric_limits<float>::infinity();
  if (blocks > 0) {
    mins.resize(blocks);
    blockLeasts(d2, n, mins.data());
    order.assign(mins.begin(), mins.end());
    std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(k - 1),
                     order.end());
    bound = order[k - 1];
  }
  for (std::size_t b = 0; b < n; b += kLeastBlock) {
    // (A block whose least lies beyond the bound passed over at once.)
    if (b / kLeastBlock < blocks && mins[b / kLeastBlock] > bound) continue;
    for (std::size_t j = b; j < std::min(n, b + kLeastBlock); ++j) {
      if (d2[j] <= bound) best.offer(d2[j]);
    }
  }
}

// The mean distances of the few grid points at positions todo, each compared with every point
// of the grid (cheaper than building a k-d tree for a few dozen).
void allPairsMeanDistances(const PointGrid& g, std::size_t want,
                           const std::vector<std::uint32_t>& todo, std::vector<double>& mean_dist) {
  const std::size_t n = g.index.size();
#pragma omp parallel if (todo.size() > 1)
  {
    NearestK best(want);
    std::vector<float> d2(n), mins, order;
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t r = 0; r < static_cast<std::ptrdiff_t>(todo.size()); ++r) {
      const std::uint32_t q = todo[static_cast<std::size_t>(r)];
      distances2(g.x.data(), g.y.data(), g.z.data(), n, g.x[q], g.y[q], g.z[q], d2.data());
      best.clear();
      offerLeast(d2.data(), n, want, mins, order, best);
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
  // Every point's mean distance is written below, or NaN: the buffer is not filled first (the
  // search writes by cell on the team, and a fill on one thread would leave the other's points
  // in its core's cache).
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  mean_dist.resize(in.size());
  finite.clear();
  // (Counted by a vector scan, on the team from CellCoords::kTeamPoints: each thread its static
  // share, the share it wrote of a compacted cloud.)
  const std::size_t N = in.size();
  std::size_t n_finite = 0;
#pragma omp parallel if (N > detail::CellCoords::kTeamPoints) reduction(+ : n_finite)
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    n_finite += countFinite(in, detail::RankedCells::share(N, team, me),
                            detail::RankedCells::share(N, team, me + 1));
  }
  if (n_finite == N) {  // (as the voxel grid's centroids)
    finite.resize(in.size());
    std::iota(finite.begin(), finite.end(), 0u);
  } else {
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (in.isFinite(i)) {
        finite.push_back(static_cast<std::uint32_t>(i));
      } else {
        mean_dist[i] = kNaN;
      }
    }
  }
  if (finite.empty()) return;
  const std::size_t want = static_cast<std::size_t>(k) + 1;  // the point itself comes first
  // (A k beyond NearestK's capacity, or a cloud beyond the keys' range: the k-d tree alone.)
  if (want > NearestK::kMax || !buildGrid(in, finite, gridCellEdge(in, finite, k, g.coords), g)) {
    for (const std::uint32_t i : finite) mean_dist[i] = kNaN;  // (where it finds no neighbour)
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
