#include "upd/maps/grid_fusion.h"

#include "keep_if.h"
#include "upd/core/openmp.h"
#include "upd/core/vector_clones.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace upd::maps {

namespace {

static_assert(static_cast<int>(core::Label::Traversable) == 0 &&
                  static_cast<int>(core::Label::NonTraversable) == 1,
              "the loops below read a labelled point's label as its non-traversable count");

// Cell codes of points that have no cell (above any cell index: at most 46000^2 cells).
constexpr std::uint32_t kInvalid = 0xFFFFFFFFu, kUnknown = 0xFFFFFFFEu, kOutside = 0xFFFFFFFDu;
constexpr std::uint32_t kNoSlot = 0xFFFFFFFFu;
// Points whose cells are computed at once, then scanned for runs while still in L1.
constexpr std::size_t kBlock = 2048;
constexpr float kInf = std::numeric_limits<float>::infinity();

// The per-point layers summed per cell, in this order in FrameCell and in vector lanes.
enum Layer { kZ, kZeta, kSlope, kCost, kLayers };

// One frame's points in one cell: per layer the sum of its finite values and their count (kZ:
// the points), the least -z and zeta (+inf: none yet), the non-traversable points. One cache
// line.
struct alignas(64) FrameCell {
  double sum[kLayers] = {};
  std::uint32_t count[kLayers] = {};
  float least[2] = {kInf, kInf};  // kZ, kZeta
  std::uint32_t n_nontrav = 0;
};

// The window in cell units: a point is in window cell (cx, cy) when floor(x / cell) = lo_x + cx
// and floor(y / cell) = lo_y + cy.
struct Window {
  double inv_cell;                // GridCellIndexer::inv_cell: the same products
  double lo_x, hi_x, lo_y, hi_y;  // whole numbers; hi = lo + cells per side
  std::uint32_t size_x;
};

// Four floats, ints and doubles as GCC vectors: one lane per layer.
typedef float Float4 __attribute__((vector_size(4 * sizeof(float))));
typedef std::int32_t Int4 __attribute__((vector_size(4 * sizeof(std::int32_t))));
typedef double Double4 __attribute__((vector_size(4 * sizeof(double))));

// Running mean over old_count earlier samples and n new ones summing to sum.
float mergeMean(float mean, std::uint32_t old_count, double sum, std::uint32_t n) {
  if (n == 0) return mean;
  if (old_count == 0) return static_cast<float>(sum / n);
  return static_cast<float>((static_cast<double>(mean) * old_count + sum) /
                            (static_cast<double>(old_count) + n));
}

std::uint32_t addSaturating(std::uint32_t a, std::uint32_t b) {
  const std::uint64_t s = static_cast<std::uint64_t>(a) + b;
  return static_cast<std::uint32_t>(
      std::min<std::uint64_t>(s, std::numeric_limits<std::uint32_t>::max()));
}

using detail::keepIf;

// floor(v) - lo where inside (v in [lo, hi)), anything elsewhere. The rounded v - lo (0 - 0
// outside, where v may be NaN or far) is at most the next whole number, so its integer part is
// one too many at most.
inline std::int32_t cellOffset(double v, double lo, bool inside) {
  const auto t = static_cast<std::int32_t>(keepIf(inside, v) - keepIf(inside, lo));
  return t - (lo + t > v);  // lo + t is exact: whole numbers
}

// The cell code of points [begin, end), the cell of GridCellIndexer exactly (the same product,
// whole-number bounds), and the counts of invalid and unknown points among them.
UPD_VECTOR_CLONES
void cellCodes(const float* __restrict x, const float* __restrict y, const float* __restrict z,
               const core::Label* __restrict label, const Window& w, std::size_t begin,
               std::size_t end, std::uint32_t* __restrict cell_of, std::uint32_t& invalid,
               std::uint32_t& unknown) {
  std::uint32_t n_invalid = 0, n_unknown = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const float px = x[i], py = y[i], pz = z[i];
    const bool finite = (px - px) + (py - py) + (pz - pz) == 0.0f;  // inf - inf, NaN: NaN
    const bool labelled = static_cast<std::uint8_t>(label[i]) <= 1;
    const double vx = px * w.inv_cell, vy = py * w.inv_cell;
    // floor(v) - lo is in [0, cells) exactly when v is in [lo, hi); NaN is outside.
    const bool inside = (vx >= w.lo_x) & (vx < w.hi_x) & (vy >= w.lo_y) & (vy < w.hi_y);
    const auto cx = static_cast<std::uint32_t>(cellOffset(vx, w.lo_x, inside));
    const auto cy = static_cast<std::uint32_t>(cellOffset(vy, w.lo_y, inside));
    const bool has_cell = finite & labelled & inside;
    const std::uint32_t none = !finite ? kInvalid : !labelled ? kUnknown : kOutside;
    cell_of[i] = none + ((cy * w.size_x + cx - none) & (0u - has_cell));
    n_invalid += !finite;
    n_unknown += finite & !labelled;
  }
  invalid = n_invalid;
  unknown = n_unknown;
}

// 1 where a run of points sharing a cell starts in [begin, end), 0 elsewhere (start[0] is
// point begin): at a point with a cell other than that of the nearest of the three points
// before it that has one. Runs so split only after three points without a cell in a row, and
// splitting a run is harmless. begin >= 3.
UPD_VECTOR_CLONES
void runStarts(const std::uint32_t* __restrict cell_of, std::size_t begin, std::size_t end,
               std::uint8_t* __restrict start) {
  for (std::size_t i = begin; i < end; ++i) {
    const std::uint32_t c1 = cell_of[i - 1], c2 = cell_of[i - 2], c3 = cell_of[i - 3];
    const std::uint32_t before = c1 < kOutside ? c1 : c2 < kOutside ? c2 : c3;
    start[i - begin] = (cell_of[i] < kOutside) & (cell_of[i] != before);
  }
}

// Adds the points [begin, end) of the cell's run to f, in point order. The sums run in local
// lanes that start from f's partial sums, so they round exactly as adding to f point by point;
// a point without this cell or value adds +0.0, which leaves a sum unchanged (sums are never
// -0.0: they start at +0.0). max z is kept as the least -z: the same comparisons, negated.
inline void addRun(FrameCell& f, const float* const* __restrict layer,
                   const core::Label* __restrict label, const std::uint32_t* __restrict cell_of,
                   std::uint32_t cell, std::size_t begin, std::size_t end) {
  const Int4 negate_z = {std::numeric_limits<std::int32_t>::min(), 0, 0, 0};
  const Float4 inf = {kInf, kInf, kInf, kInf};
  Int4 inf_bits;
  std::memcpy(&inf_bits, &inf, sizeof inf_bits);
  Double4 sum;
  Int4 count;
  // (Built in registers: a copy of f.least over a stored vector of inf would be read back as one
  // vector from two stores, which the store buffer cannot forward: a stall at every run.)
  Float4 least = {f.least[0], f.least[1], kInf, kInf};
  std::memcpy(&sum, f.sum, sizeof sum);
  std::memcpy(&count, f.count, sizeof count);
  std::uint32_t n_nontrav = f.n_nontrav;
  const float *const z = layer[kZ], *const zeta = layer[kZeta], *const slope = layer[kSlope],
                     *const cost = layer[kCost];
  const Int4 run_cell = Int4{} + static_cast<std::int32_t>(cell);
  for (std::size_t i = begin; i < end; ++i) {
    const Int4 in = run_cell == static_cast<std::int32_t>(cell_of[i]);  // all lanes alike
    n_nontrav += static_cast<std::uint8_t>(label[i]) & in[0];
    const Float4 v = {z[i], zeta[i], slope[i], cost[i]};
    const Int4 ok = (v - v == 0) & in;  // finite (inf - inf and NaN are NaN) and in the cell
    Int4 bits;
    std::memcpy(&bits, &v, sizeof bits);
    const Int4 kept_bits = bits & ok;  // the value, or +0.0
    const Int4 candidate_bits = ((bits ^ negate_z) & ok) | (inf_bits & ~ok);  // -z, zeta or +inf
    Float4 kept, candidate;
    std::memcpy(&kept, &kept_bits, sizeof kept);
    std::memcpy(&candidate, &candidate_bits, sizeof candidate);
    sum += Double4{kept[0], kept[1], kept[2], kept[3]};
    count -= ok;
    least = candidate < least ? candidate : least;
  }
  std::memcpy(f.sum, &sum, sizeof sum);
  std::memcpy(f.count, &count, sizeof count);
  f.least[0] = least[0], f.least[1] = least[1];
  f.n_nontrav = n_nontrav;
}

// What step 2 of integrateScan reads, and the tables it fills besides the FrameCells.
struct RunInputs {
  const std::uint32_t* cell_of;
  const float* layer[kLayers];  // a layer the view lacks: NaN for every point
  const core::Label* label;
  double inv_size_x;
  std::uint32_t size_x;
  std::uint32_t* slots;     // per cell: its FrameCell, or kNoSlot
  std::uint32_t* row_span;  // per row: the touched columns [first, end); none: 0, 0
};

// Adds the runs of one chunk (starting at run_begin[0, count), the last one ending at
// chunk_end) that fall in the rows [row_lo, row_hi) of this thread to their FrameCells,
// appending those of newly touched cells to frame.
UPD_VECTOR_CLONES
void addChunkRuns(const std::size_t* run_begin, std::size_t count, std::size_t chunk_end,
                  const RunInputs& in, std::uint32_t row_lo, std::uint32_t row_hi,
                  std::vector<FrameCell>& frame) {
  for (std::size_t r = 0; r < count; ++r) {
    const std::uint32_t cell = in.cell_of[run_begin[r]];
    // cell / size_x without a division: (cell + 0.5) / size_x is 0.5 / size_x or more from a
    // whole number, far more than the product's rounding.
    const auto row = static_cast<std::uint32_t>((cell + 0.5) * in.inv_size_x);
    if (row < row_lo || row >= row_hi) continue;
    std::uint32_t& slot = in.slots[cell];
    if (slot == kNoSlot) {
      slot = static_cast<std::uint32_t>(frame.size());
      frame.emplace_back();
      const std::uint32_t cx = cell - row * in.size_x;
      std::uint32_t* const span = in.row_span + 2 * row;
      span[0] = span[1] == 0 ? cx : std::min(span[0], cx);
      span[1] = std::max(span[1], cx + 1);
    }
    const std::size_t end = r + 1 < count ? run_begin[r + 1] : chunk_end;
    addRun(frame[slot], in.layer, in.label, in.cell_of, cell, run_begin[r], end);
  }
}

// The buffers integrateScan shares among its team: the calling thread's, kept for its next
// frame (taken before the parallel region).
struct ScanBuffers {
  std::uint32_t* cell_of;       // per point: its cell code
  std::size_t* run_begin;       // per point slot: where the runs of each thread's chunk start
  std::size_t* run_count;       // per thread: the runs of its chunk
  std::uint32_t* runs_per_row;  // per thread, per grid row: the runs in that row
  RunInputs in;                 // what step 2 reads (cell_of among them) and fills
};

ScanBuffers takeScanBuffers(const PointsWorld& points, int size_x, int size_y, int max_team) {
  static thread_local std::vector<std::uint32_t> point_cell, slot_of_cell, row_span_of;
  static thread_local std::vector<std::size_t> run_begin_of, run_count_of;
  static thread_local std::vector<std::uint32_t> runs_per_row_of;  // per thread, per grid row
  static thread_local std::vector<float> no_values;  // NaN: the layer a view lacks
  point_cell.resize(points.size);
  run_begin_of.resize(points.size);
  run_count_of.resize(static_cast<std::size_t>(max_team));
  runs_per_row_of.resize(static_cast<std::size_t>(max_team) * size_y);
  const std::size_t n_cells = static_cast<std::size_t>(size_x) * size_y;
  if (slot_of_cell.size() < n_cells) slot_of_cell.assign(n_cells, kNoSlot);
  if (row_span_of.size() < 2 * static_cast<std::size_t>(size_y)) {
    row_span_of.assign(2 * static_cast<std::size_t>(size_y), 0);
  }
  if (!(points.zeta && points.slope_rad && points.cost) && no_values.size() < points.size) {
    no_values.assign(points.size, std::numeric_limits<float>::quiet_NaN());
  }
  const RunInputs in{point_cell.data(),
                     {points.z, points.zeta ? points.zeta : no_values.data(),
                      points.slope_rad ? points.slope_rad : no_values.data(),
                      points.cost ? points.cost : no_values.data()},
                     points.label,
                     1.0 / size_x,
                     static_cast<std::uint32_t>(size_x),
                     slot_of_cell.data(),
                     row_span_of.data()};
  return ScanBuffers{point_cell.data(), run_begin_of.data(), run_count_of.data(),
                     runs_per_row_of.data(), in};
}

// Step 1 for the chunk [chunk_begin, chunk_end): the cell of every point (or why it has none),
// where the runs of points sharing a cell start (into my_runs; returns their number), and the
// runs per grid row (into my_rows, size_y entries). Adds the invalid and unknown points.
std::size_t findChunkRuns(const PointsWorld& points, const Window& window, double inv_size_x,
                          std::size_t chunk_begin, std::size_t chunk_end, std::uint32_t* cell_of,
                          std::size_t* my_runs, std::uint32_t* my_rows, int size_y,
                          std::size_t& invalid, std::size_t& unknown) {
  std::size_t n_runs = 0;
  std::fill(my_rows, my_rows + size_y, 0u);
  std::uint8_t starts[kBlock];
  for (std::size_t block = chunk_begin; block < chunk_end; block += kBlock) {
    const std::size_t block_end = std::min(chunk_end, block + kBlock);
    std::uint32_t block_invalid, block_unknown;
    cellCodes(points.x, points.y, points.z, points.label, window, block, block_end, cell_of,
              block_invalid, block_unknown);
    invalid += block_invalid;
    unknown += block_unknown;
    // The chunk's first points have fewer than three points before them in the chunk.
    std::size_t i = block;
    for (std::uint32_t last = kInvalid; i < std::min(block_end, chunk_begin + 3); ++i) {
      starts[i - block] = (cell_of[i] < kOutside) & (cell_of[i] != last);
      last = cell_of[i] < kOutside ? cell_of[i] : last;
    }
    runStarts(cell_of, i, block_end, starts + (i - block));
    const std::size_t block_runs = n_runs;
    for (i = block; i < block_end; ++i) {
      my_runs[n_runs] = i;  // kept only where a run starts: no branch
      n_runs += starts[i - block];
    }
    for (std::size_t r = block_runs; r < n_runs; ++r) {
      ++my_rows[static_cast<std::uint32_t>((cell_of[my_runs[r]] + 0.5) * inv_size_x)];
    }
  }
  return n_runs;
}

// The first grid row with at least `share` runs (of all team chunks) in the rows before it.
std::uint32_t rowAfter(std::size_t share, const std::uint32_t* runs_per_row, int team,
                       int size_y) {
  std::size_t before = 0;
  for (int row = 0; row < size_y; ++row) {
    if (before >= share) return static_cast<std::uint32_t>(row);
    for (int c = 0; c < team; ++c) {
      before += runs_per_row[static_cast<std::size_t>(c) * size_y + row];
    }
  }
  return static_cast<std::uint32_t>(size_y);
}

// Points and cells counted by step 3 (one thread's share, summed by the reduction).
struct CellCounts {
  std::size_t used = 0, updated = 0, hit = 0, sparse = 0;
};

// One frame's log-odds update and running means of one cell from its FrameCell.
inline void updateCell(GridCell& c, const FrameCell& f, double update, double time_s,
                       const FusionParams& params) {
  const std::uint32_t n = f.count[kZ];
  c.logodds_nontrav = fuseLogOdds(c.logodds_nontrav, update, params);
  c.elevation_m = mergeMean(c.elevation_m, c.hits, f.sum[kZ], n);
  c.elevation_max_m = std::fmax(c.elevation_max_m, -f.least[kZ]);
  if (f.count[kZeta] > 0) c.zeta_min = std::fmin(c.zeta_min, f.least[kZeta]);
  c.zeta_mean = mergeMean(c.zeta_mean, c.zeta_count, f.sum[kZeta], f.count[kZeta]);
  c.slope_rad = mergeMean(c.slope_rad, c.slope_count, f.sum[kSlope], f.count[kSlope]);
  c.cost_mean = mergeMean(c.cost_mean, c.cost_count, f.sum[kCost], f.count[kCost]);
  c.hits = addSaturating(c.hits, n);
  c.zeta_count = addSaturating(c.zeta_count, f.count[kZeta]);
  c.slope_count = addSaturating(c.slope_count, f.count[kSlope]);
  c.cost_count = addSaturating(c.cost_count, f.count[kCost]);
  c.last_seen_s = time_s;
}

// Step 3 for the rows [row_lo, row_hi): one update per touched cell, in grid order (the grid is
// larger than the caches, and sequential access lets the hardware prefetch); resets the slot
// table and row spans it reads.
void updateRows(TraversabilityGrid& grid, const std::vector<FrameCell>& frame,
                const RunInputs& in, std::uint32_t row_lo, std::uint32_t row_hi, double time_s,
                const FusionParams& params, CellCounts& counts) {
  const std::size_t size_x = in.size_x;
  for (int cy = static_cast<int>(row_lo); cy < static_cast<int>(row_hi); ++cy) {
    std::uint32_t* const row_slots = in.slots + static_cast<std::size_t>(cy) * size_x;
    std::uint32_t* const span = in.row_span + 2 * cy;
    const int first = static_cast<int>(span[0]), last = static_cast<int>(span[1]);
    span[0] = span[1] = 0;
    for (int cx = first; cx < last; ++cx) {
      // FrameCells are in first-touch order, and step 2 has streamed the points through the
      // caches since: fetch them a few cells ahead.
      const std::uint32_t ahead = cx + 8 < last ? row_slots[cx + 8] : kNoSlot;
      if (ahead != kNoSlot) __builtin_prefetch(frame.data() + ahead);
      if (row_slots[cx] == kNoSlot) continue;
      const FrameCell& f = frame[row_slots[cx]];
      row_slots[cx] = kNoSlot;
      const std::uint32_t n = f.count[kZ];
      counts.used += n;
      const double update = frameLogOddsUpdate(f.n_nontrav, n - f.n_nontrav, params);
      if (update == 0.0) {
        ++counts.sparse;
        continue;
      }
      updateCell(grid.at(cx, cy), f, update, time_s, params);
      ++counts.updated;
      if (update > 0) ++counts.hit;
    }
  }
}

}  // namespace

GridFusionStats integrateScan(TraversabilityGrid& grid, const PointsWorld& points,
                              const Eigen::Vector2d& robot_xy, double time_s,
                              const FusionParams& params) {
  params.validate();
  points.validate();
  core::requireParam(std::isfinite(time_s), "integrateScan", "time_s", time_s, "must be finite");
  GridFusionStats stats;
  stats.window_moved = grid.moveTo(robot_xy);

  // Aggregate first: one log-odds update per cell per frame, whatever its point count.
  const int size_x = grid.sizeX(), size_y = grid.sizeY();
  const GridCellIndexer ix = grid.indexer();
  const Window window{ix.inv_cell, ix.i0, ix.i0 + ix.size_x, ix.j0, ix.j0 + ix.size_y,
                      static_cast<std::uint32_t>(size_x)};
  const ScanBuffers buf = takeScanBuffers(points, size_x, size_y, core::openmp::maxThreads());
  const RunInputs& run_inputs = buf.in;

  std::size_t invalid = 0, unknown = 0, used = 0, updated = 0, hit = 0, sparse = 0;
#pragma omp parallel reduction(+ : invalid, unknown, used, updated, hit, sparse)
  {
    const int team = core::openmp::teamSize(), me = core::openmp::threadIndex();
    // 1. Each thread takes a chunk of the points: their cells and where their runs start.
    const std::size_t chunk_begin = points.size * me / team,
                      chunk_end = points.size * (me + 1) / team;
    buf.run_count[me] = findChunkRuns(points, window, run_inputs.inv_size_x, chunk_begin,
                                      chunk_end, buf.cell_of, buf.run_begin + chunk_begin,
                                      buf.runs_per_row + static_cast<std::size_t>(me) * size_y,
                                      size_y, invalid, unknown);
#pragma omp barrier

    // 2. Per-frame sums per touched cell. Each thread takes a range of the grid's rows holding
    // about its share of the runs: every thread reads the runs of all chunks and takes those
    // in its rows, in point order, so the result does not depend on the number of threads. A
    // dense slot table over the grid (shared: each cell belongs to one thread; reset after
    // use) points each touched cell to its FrameCell; per row, the span of touched columns.
    std::size_t total_runs = 0;
    for (int c = 0; c < team; ++c) total_runs += buf.run_count[c];
    const std::uint32_t row_lo =
        me == 0 ? 0 : rowAfter(total_runs * me / team, buf.runs_per_row, team, size_y);
    const std::uint32_t row_hi =
        me == team - 1 ? static_cast<std::uint32_t>(size_y)
                       : rowAfter(total_runs * (me + 1) / team, buf.runs_per_row, team, size_y);
    static thread_local std::vector<FrameCell> frame;  // this thread's own
    frame.clear();
    for (int c = 0; c < team; ++c) {
      addChunkRuns(buf.run_begin + points.size * c / team, buf.run_count[c],
                   points.size * (c + 1) / team, run_inputs, row_lo, row_hi, frame);
    }

    // 3. One update per touched cell.
    CellCounts counts;
    updateRows(grid, frame, run_inputs, row_lo, row_hi, time_s, params, counts);
    used += counts.used;
    updated += counts.updated;
    hit += counts.hit;
    sparse += counts.sparse;
  }
  stats.points_invalid = invalid;
  stats.points_unknown = unknown;
  stats.points_used = used;
  stats.points_outside = points.size - invalid - unknown - used;  // finite, labelled, outside
  stats.cells_updated = updated;
  stats.cells_hit = hit;
  stats.cells_too_sparse = sparse;
  return stats;
}

}  // namespace upd::maps
