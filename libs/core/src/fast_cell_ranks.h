// Private to libs/core: the occupied cells of a box numbered by rank (RankedCells) and the
// grouping of items by cell (listByCell) on the OpenMP team, for the outlier filter's grid and
// the grid normals. Both give the same result on any number of threads.
//
// The functions whose names end in Team are called by every thread of a team, inside a parallel
// region (or by one thread outside any); they synchronize the team themselves and return when
// their result is complete.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fast_cell_map.h"
#include "upd/core/openmp.h"

namespace upd::core::detail {

/// The set bits of v, in plain arithmetic (the library's x86-64 baseline has no POPCNT
/// instruction: GCC's builtin is then a call into libgcc).
inline std::uint32_t countBits(std::uint64_t v) {
  v = v - ((v >> 1) & 0x5555555555555555ull);
  v = (v & 0x3333333333333333ull) + ((v >> 2) & 0x3333333333333333ull);
  v = (v + (v >> 4)) & 0x0f0f0f0f0f0f0f0full;
  return static_cast<std::uint32_t>((v * 0x0101010101010101ull) >> 56);
}

/// The occupied cells of the box [lo, hi] widened by margin cells on every side, one bit each
/// (x fastest), numbered by rank: a cell's id is the number of occupied cells before it in the
/// box. A cell and its neighbours by a load and a population count each, at offsets fixed per
/// box, from 2 bits per cell of the box (a Kinect frame's grids: tens of KB, in the cache) where
/// a table of 32-bit ids would take 32. reset() declines (false) where the box would hold more
/// than kCellsPerPoint cells per point (far lone points widen it): the caller then uses the hash
/// (CellGrid).
class RankedCells {
 public:
  static constexpr std::size_t kCellsPerPoint = 64;

  /// Sizes the table for the box (nothing marked); false where it declines the box.
  bool reset(const std::int32_t (&box_lo)[3], const std::int32_t (&box_hi)[3], int margin,
             std::size_t n_points) {
    std::int64_t dim[3];
    double volume = 1;
    for (int a = 0; a < 3; ++a) {
      dim[a] = std::int64_t{box_hi[a]} - box_lo[a] + 1 + 2 * margin;
      volume *= static_cast<double>(dim[a]);
    }
    n_cells_ = 0;
    if (volume > static_cast<double>(kCellsPerPoint * n_points + 4096)) {
      words_.clear();
      return false;
    }
    words_.resize(static_cast<std::size_t>(volume) / 64 + 1);
    for (int a = 0; a < 3; ++a) lo_[a] = std::int64_t{box_lo[a]} - margin;
    sy_ = dim[0], sz_ = dim[0] * dim[1];
    return true;
  }
  std::size_t index(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
    return static_cast<std::size_t>((cx - lo_[0]) + (cy - lo_[1]) * sy_ + (cz - lo_[2]) * sz_);
  }
  std::int64_t offset(std::int64_t dx, std::int64_t dy, std::int64_t dz) const {
    return dx + dy * sy_ + dz * sz_;
  }
  /// The id of the cell at index, or kNoIndex where it is empty.
  std::uint32_t id(std::size_t index) const {
    const Word& w = words_[index / 64];
    const std::uint64_t bit = std::uint64_t{1} << (index % 64);
    if ((w.bits & bit) == 0) return kNoIndex;
    return w.before + countBits(w.bits & (bit - 1));
  }
  /// The ids of the occupied cells at index at + offsets[j], in the offsets' order, into out;
  /// returns their number. (out has room for every offset: each one's rank is stored and the
  /// count moves on where the cell is occupied, with no branch on the cells' pattern.)
  std::size_t occupiedIds(std::size_t at, const std::int64_t* offsets, std::size_t n_offsets,
                          std::uint32_t* out) const {
    std::size_t n = 0;
    for (std::size_t j = 0; j < n_offsets; ++j) {
      const std::size_t index = at + static_cast<std::size_t>(offsets[j]);
      const Word& w = words_[index / 64];
      const std::uint64_t bit = std::uint64_t{1} << (index % 64);
      out[n] = w.before + countBits(w.bits & (bit - 1));
      n += (w.bits & bit) != 0 ? 1 : 0;
    }
    return n;
  }
  /// The ids of the cells at index b, b + 1 and b + 2 (kNoIndex where empty): one population
  /// count where the three share a word.
  void threeIds(std::size_t b, std::uint32_t (&out)[3]) const {
    const std::size_t bit0 = b % 64;
    if (bit0 > 61) {
      for (std::size_t k = 0; k < 3; ++k) out[k] = id(b + k);
      return;
    }
    const Word& w = words_[b / 64];
    std::uint32_t rank = w.before + countBits(w.bits & ((std::uint64_t{1} << bit0) - 1));
    const std::uint64_t three = w.bits >> bit0;
    for (std::size_t k = 0; k < 3; ++k) out[k] = (three >> k) & 1 ? rank++ : kNoIndex;
  }
  std::size_t size() const { return n_cells_; }
  /// The cell at index (the inverse of index()).
  void cellAt(std::size_t index, std::int32_t* xyz) const {
    const auto i = static_cast<std::int64_t>(index);
    const std::int64_t in_plane = i % sz_;
    xyz[0] = static_cast<std::int32_t>(in_plane % sy_ + lo_[0]);
    xyz[1] = static_cast<std::int32_t>(in_plane / sy_ + lo_[1]);
    xyz[2] = static_cast<std::int32_t>(i / sz_ + lo_[2]);
  }
  /// Team: the coordinates of every marked cell into xyz, 3 a cell in id order (size() cells);
  /// each thread those of its static share of the words.
  void cellsTeam(std::int32_t* xyz) const {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    for (std::size_t w = share(words_.size(), team, me); w < share(words_.size(), team, me + 1);
         ++w) {
      std::uint32_t id = words_[w].before;
      for (std::uint64_t bits = words_[w].bits; bits != 0; bits &= bits - 1, ++id) {
        cellAt(64 * w + static_cast<std::size_t>(__builtin_ctzll(bits)), xyz + 3 * std::size_t{id});
      }
    }
  }

  /// What index_of gives for an item without a cell.
  static constexpr std::size_t kSkip = ~std::size_t{0};

  /// Team: marks the cells at index_of(i) of the items [0, n) and numbers them. Each thread
  /// marks the items of its static share in bits of its own; the union and the ranks go by
  /// static shares of the words.
  template <class IndexOf>
  void buildTeam(std::size_t n, IndexOf&& index_of) {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t W = words_.size();
#pragma omp single
    {
      if (marks_.size() < static_cast<std::size_t>(team)) marks_.resize(team);
      share_cells_.assign(static_cast<std::size_t>(team), 0);
    }
    std::vector<std::uint64_t>& m = marks_[static_cast<std::size_t>(me)];
    m.assign(W, 0);
    for (std::size_t i = share(n, team, me); i < share(n, team, me + 1); ++i) {
      const std::size_t b = index_of(i);
      if (b != kSkip) m[b / 64] |= std::uint64_t{1} << (b % 64);
    }
#pragma omp barrier
    std::uint32_t count = 0;
    const std::size_t w0 = share(W, team, me), w1 = share(W, team, me + 1);
    for (std::size_t w = w0; w < w1; ++w) {
      std::uint64_t bits = marks_[0][w];
      for (int t = 1; t < team; ++t) bits |= marks_[static_cast<std::size_t>(t)][w];
      words_[w].bits = bits;
      words_[w].before = count;
      count += countBits(bits);
    }
    share_cells_[static_cast<std::size_t>(me)] = count;
#pragma omp barrier
    std::uint32_t base = 0;
    for (int t = 0; t < me; ++t) base += share_cells_[static_cast<std::size_t>(t)];
    for (std::size_t w = w0; w < w1; ++w) words_[w].before += base;
#pragma omp single
    {
      std::size_t total = 0;
      for (const std::uint32_t c : share_cells_) total += c;
      n_cells_ = total;
    }
  }

  /// The first of the items [0, n) in static share s of team shares.
  static std::size_t share(std::size_t n, int team, int s) {
    return n * static_cast<std::size_t>(s) / static_cast<std::size_t>(team);
  }

 private:
  struct Word {
    std::uint64_t bits = 0;
    std::uint32_t before = 0;  // the occupied cells of the words before
    std::uint32_t unused = 0;
  };
  std::vector<Word> words_;
  std::int64_t lo_[3] = {0, 0, 0};
  std::int64_t sy_ = 0, sz_ = 0;  // strides of y and z
  std::size_t n_cells_ = 0;
  std::vector<std::vector<std::uint64_t>> marks_;  // by thread
  std::vector<std::uint32_t> share_cells_;         // by thread: the cells of its words
};

/// The per-thread counts of listByCellTeam, kept from call to call.
struct TeamCellCounts {
  std::vector<std::vector<std::uint32_t>> by_thread;
};

/// Team: listByCell (the same lists). Each thread counts the items of its static share by cell;
/// a cell's items then go share by share, in item order within each.
template <class CellOfItem>
void listByCellTeam(std::size_t n_items, std::size_t n_cells, CellOfItem&& cell,
                    CellLists& out, TeamCellCounts& counts) {
  const int team = openmp::teamSize(), me = openmp::threadIndex();
#pragma omp single
  {
    if (counts.by_thread.size() < static_cast<std::size_t>(team)) counts.by_thread.resize(team);
    out.start.resize(n_cells + 1);
    out.start[0] = 0;
  }
  std::vector<std::uint32_t>& next = counts.by_thread[static_cast<std::size_t>(me)];
  next.assign(n_cells, 0);
  const std::size_t b = RankedCells::share(n_items, team, me);
  const std::size_t e = RankedCells::share(n_items, team, me + 1);
  for (std::size_t i = b; i < e; ++i) {
    const std::uint32_t c = cell(i);
    if (c != kNoIndex) ++next[c];
  }
#pragma omp barrier
  // Each cell's count, and each share's first place among the cell's items (from the cell's
  // start, added when the items are placed).
  for (std::size_t c = RankedCells::share(n_cells, team, me);
       c < RankedCells::share(n_cells, team, me + 1); ++c) {
    std::uint32_t run = 0;
    for (int t = 0; t < team; ++t) {
      std::uint32_t& k = counts.by_thread[static_cast<std::size_t>(t)][c];
      const std::uint32_t here = k;
      k = run, run += here;
    }
    out.start[c + 1] = run;
  }
#pragma omp barrier
#pragma omp single
  {
    for (std::size_t c = 0; c < n_cells; ++c) out.start[c + 1] += out.start[c];
    out.order.resize(out.start[n_cells]);
  }
  for (std::size_t i = b; i < e; ++i) {
    const std::uint32_t c = cell(i);
    if (c != kNoIndex) out.order[out.start[c] + next[c]++] = static_cast<std::uint32_t>(i);
  }
#pragma omp barrier
}

/// The cell coordinates of items: item i's at x[i * stride], y[i * stride], z[i * stride].
struct CellRows {
  const std::int32_t *x, *y, *z;
  std::size_t stride;
};

/// The ids of the cells of items [b, e) that have one (cell_of[i] not kNoIndex) into cell_of.
/// (A function of its own, cloned: on x86-64-v3 and up GCC makes countBits one POPCNT.)
void rankedIds(const RankedCells& ranks, const CellRows& rows, std::size_t b, std::size_t e,
               std::uint32_t* cell_of);

/// Team: the cells of the items [0, n) that have one (cell_of[i] not kNoIndex) marked in ranks
/// (reset for their box) and numbered by rank into cell_of; the items grouped by cell into lists;
/// each cell's coordinates into cell_xyz (3 a cell). Then sized(number of cells) on one thread,
/// and copy(b, e) on each thread for its static share of the listed items. The same on any
/// number of threads.
template <class Sized, class Copy>
void rankListAndCopyTeam(RankedCells& ranks, const CellRows& rows, std::size_t n,
                         std::uint32_t* cell_of, CellLists& lists, TeamCellCounts& counts,
                         std::vector<std::int32_t>& cell_xyz, Sized&& sized, Copy&& copy) {
  ranks.buildTeam(n, [&](std::size_t i) {
    const std::size_t at = i * rows.stride;
    return cell_of[i] == kNoIndex ? RankedCells::kSkip
                                  : ranks.index(rows.x[at], rows.y[at], rows.z[at]);
  });
  const int team = openmp::teamSize(), me = openmp::threadIndex();
  rankedIds(ranks, rows, RankedCells::share(n, team, me), RankedCells::share(n, team, me + 1),
            cell_of);
#pragma omp barrier
  listByCellTeam(
      n, ranks.size(), [&](std::size_t i) { return cell_of[i]; }, lists, counts);
  const std::size_t n_cells = ranks.size();
#pragma omp single
  {
    cell_xyz.resize(3 * n_cells);
    sized(n_cells);
  }
#pragma omp for schedule(static) nowait
  for (std::size_t c = 0; c < n_cells; ++c) {
    const std::size_t at = lists.order[lists.start[c]] * rows.stride;
    cell_xyz[3 * c] = rows.x[at], cell_xyz[3 * c + 1] = rows.y[at], cell_xyz[3 * c + 2] = rows.z[at];
  }
  const std::size_t m = lists.order.size();
  copy(RankedCells::share(m, team, me), RankedCells::share(m, team, me + 1));
#pragma omp barrier
}

}  // namespace upd::core::detail
