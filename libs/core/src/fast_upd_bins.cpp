// The fast UPD's first stage: the points binned into the lattice's cells, with per cell the
// sums the ball sums read (CellSums), in fixed chunks merged in chunk order. binRange is
// binCells (fast_cell_map.h) specialized for the lattice: the cell coordinates of a stripe of
// points in one vector loop, and the sums of a run of points in one cell added at once.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>

#include "fast_upd_internal.h"
#include "upd/core/openmp.h"

namespace upd::core::detail {

namespace {

// A stripe of points in lattice terms, the first pass of binRange: each point's cell (cx, cy,
// cz at j + 1: integers as floats, exact below 2^24; cx = kOutside for a point that is not
// finite or lies beyond the key range; index 0 holds the previous stripe's last cell), whether
// it starts a run (its cell differs from the point before's), and its contribution to the
// CellSums of its cell, in their order (count, normal, position inside the cell, its
// products), zeros where the normal is invalid. Each row has a vector of slack after the
// stripe (a run's last vector reads it, masked).
constexpr float kOutside = -2.f * kMaxCoord;
constexpr std::size_t kStripe = 256;
constexpr std::size_t kTerms = 13;
constexpr std::size_t kRunLanes = 8;
struct Stripe {
  float cx[kStripe + 1], cy[kStripe + 1], cz[kStripe + 1];
  std::uint8_t starts[kStripe + 8];  // starts[n] = 1: the end of the stripe's last run
  float term[kTerms][kStripe + kRunLanes];
};

// A point's lattice coordinates within the key range; NaN and infinity fail the test too. (&
// rather than &&, on ints for clang's -Wbitwise-instead-of-logical: no branch, so the loops
// that call it vectorize.)
inline bool inLattice(float gx, float gy, float gz) {
  return (static_cast<int>(std::fabs(gx) < kMaxCoord) & static_cast<int>(std::fabs(gy) < kMaxCoord) &
          static_cast<int>(std::fabs(gz) < kMaxCoord)) != 0;
}

// Fills the stripe for n points; returns true when a finite point lies beyond the key range.
UPD_VECTOR_CLONES
bool toLattice(const float* __restrict x, const float* __restrict y, const float* __restrict z,
               const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
               const Lattice& lat, std::size_t n, Stripe& __restrict s) {
  int beyond = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const float gx = lat.gx(x[j]), gy = lat.gy(y[j]), gz = lat.gz(z[j]);
    // (Floors as floats, everything loaded and computed before it is selected: no branch, so
    // the loop vectorizes.)
    const bool inside = inLattice(gx, gy, gz);
    const bool finite = (static_cast<int>(x[j] - x[j] == 0.f) &
                         static_cast<int>(y[j] - y[j] == 0.f) &
                         static_cast<int>(z[j] - z[j] == 0.f)) != 0;
    beyond |= static_cast<int>(!inside) & static_cast<int>(finite);
    const float fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
    const float ax = nx[j], ay = ny[j], az = nz[j];
    const bool valid = ax == ax;
    const float px = valid ? gx - fx : 0.f, py = valid ? gy - fy : 0.f, pz = valid ? gz - fz : 0.f;
    s.cx[j + 1] = inside ? fx : kOutside;
    s.cy[j + 1] = fy, s.cz[j + 1] = fz;
    auto& t = s.term;
    t[0][j] = valid ? 1.f : 0.f;
    t[1][j] = valid ? ax : 0.f, t[2][j] = valid ? ay : 0.f, t[3][j] = valid ? az : 0.f;
    t[4][j] = px, t[5][j] = py, t[6][j] = pz;
    t[7][j] = px * px, t[8][j] = px * py, t[9][j] = px * pz, t[10][j] = py * py;
    t[11][j] = py * pz, t[12][j] = pz * pz;
  }
  for (std::size_t j = 0; j < n; ++j) {
    // (An outside point's cy and cz are whatever its floors gave: its cx decides.)
    const bool outside = s.cx[j + 1] == kOutside;
    const bool same = (static_cast<int>(s.cx[j + 1] == s.cx[j]) &
                       (static_cast<int>(outside) | (static_cast<int>(s.cy[j + 1] == s.cy[j]) &
                                                     static_cast<int>(s.cz[j + 1] == s.cz[j])))) !=
                      0;
    s.starts[j] = same ? 0 : 1;
  }
  return beyond != 0;
}

// The first run start after j (starts[n] is set): 8 flags at a time, most runs being longer.
__attribute__((always_inline)) inline std::size_t nextStart(const std::uint8_t* starts, std::size_t j) {
  for (;; j += 8) {
    std::uint64_t eight;
    std::memcpy(&eight, starts + j, sizeof eight);
    if (eight != 0) return j + static_cast<std::size_t>(__builtin_ctzll(eight)) / 8;
  }
}

typedef float RunLanes __attribute__((vector_size(kRunLanes * sizeof(float))));
typedef std::int32_t RunMask __attribute__((vector_size(kRunLanes * sizeof(std::int32_t))));
typedef float RunQuad __attribute__((vector_size(4 * sizeof(float))));

// The sums of four vectors' lanes, ((v0 + v4) + (v2 + v6)) + ((v1 + v5) + (v3 + v7)) each, as
// one vector: the halves added, then two rounds of pairwise sums across the vectors.
__attribute__((always_inline)) inline RunQuad laneSums(const RunLanes& a, const RunLanes& b, const RunLanes& c,
                        const RunLanes& d) {
  const auto half = [](const RunLanes& v) {
    return __builtin_shufflevector(v, v, 0, 1, 2, 3) + __builtin_shufflevector(v, v, 4, 5, 6, 7);
  };
  const auto pairs = [](const RunQuad& x, const RunQuad& y) {
    return __builtin_shufflevector(x, y, 0, 2, 4, 6) + __builtin_shufflevector(x, y, 1, 3, 5, 7);
  };
  return pairs(pairs(half(a), half(b)), pairs(half(c), half(d)));
}

// The terms of the stripe's points [j, e) (one run) added to the sums of their cell: a vector
// of kRunLanes points at a time, the last vector's lanes beyond e masked to +0; then the lanes
// added up, four terms at a time.
__attribute__((always_inline)) inline void addRun(const Stripe& s, std::size_t j, std::size_t e, CellSums& cell) {
  RunLanes acc[kTerms + 3] = {};
  for (; j + kRunLanes <= e; j += kRunLanes) {
    for (std::size_t k = 0; k < kTerms; ++k) {
      RunLanes v;
      std::memcpy(&v, &s.term[k][j], sizeof v);
      acc[k] += v;
    }
  }
  if (j < e) {
    const RunMask lanes = {0, 1, 2, 3, 4, 5, 6, 7};
    const RunMask keep = lanes < static_cast<std::int32_t>(e - j);
    for (std::size_t k = 0; k < kTerms; ++k) {
      RunLanes v;
      std::memcpy(&v, &s.term[k][j], sizeof v);
      acc[k] += (RunLanes)((RunMask)v & keep);
    }
  }
  const RunQuad q0 = laneSums(acc[0], acc[1], acc[2], acc[3]);
  if (!(q0[0] > 0.f)) return;  // no valid normal in the run: nothing to add
  const RunQuad q1 = laneSums(acc[4], acc[5], acc[6], acc[7]);
  const RunQuad q2 = laneSums(acc[8], acc[9], acc[10], acc[11]);
  const RunQuad q3 = laneSums(acc[12], acc[13], acc[14], acc[15]);
  cell.add({q0[0], q0[1], q0[2], q0[3], q1[0], q1[1], q1[2], q1[3], q2[0], q2[1], q2[2], q2[3],
            q3[0]});
}

// A stripe's runs of points in one cell, found before they are summed (so that the sums' loop
// makes no call and keeps its vectors in registers).
struct Runs {
  std::uint16_t begin[kStripe], end[kStripe];
  std::uint32_t cell[kStripe];
  std::size_t n = 0;
};

// What binRange works in: the calling thread's, kept (thread_local, reached once per range).
struct StripeBuffers {
  Stripe s;
  Runs runs;
};

// Bins points [begin, end) into b, writing each point's cell (local to b) into cell_of.
// Consecutive points (image rows, scan lines) mostly share a cell: the stripe's runs of points
// in one cell are found from the start flags, 8 at a time, the hash map is consulted once per
// run, and a run's terms are summed a vector of points at a time. Returns false when a point
// lies beyond the lattice's key range (it is left out).
UPD_VECTOR_CLONES
bool binRange(const PointCloud& cloud, const Normals& normals, const Lattice& lat,
              std::size_t begin, std::size_t end, Bins& b, std::uint32_t* cell_of,
              StripeBuffers& buf) {
  Stripe& s = buf.s;
  Runs& runs = buf.runs;
  std::uint32_t last = kNoIndex;  // the cell of the run
  bool fits = true;
  s.cx[0] = kOutside, s.cy[0] = s.cz[0] = 0.f;  // (no run before the range)
  for (std::size_t s0 = begin; s0 < end; s0 += kStripe) {
    const std::size_t n = std::min(kStripe, end - s0);
    if (toLattice(&cloud.x[s0], &cloud.y[s0], &cloud.z[s0], &normals.nx[s0], &normals.ny[s0],
                  &normals.nz[s0], lat, n, s)) {
      fits = false;
    }
    s.starts[n] = 1;
    runs.n = 0;
    for (std::size_t j = 0; j < n;) {
      const std::size_t e = nextStart(s.starts, j + 1);
      if (s.starts[j]) {
        last = s.cx[j + 1] == kOutside
                   ? kNoIndex
                   : b.cellOf(static_cast<std::int32_t>(s.cx[j + 1]),
                              static_cast<std::int32_t>(s.cy[j + 1]),
                              static_cast<std::int32_t>(s.cz[j + 1]));
      }
      std::fill(cell_of + s0 + j, cell_of + s0 + e, last);
      if (last != kNoIndex) {
        runs.begin[runs.n] = static_cast<std::uint16_t>(j);
        runs.end[runs.n] = static_cast<std::uint16_t>(e);
        runs.cell[runs.n++] = last;
      }
      j = e;
    }
    for (std::size_t r = 0; r < runs.n; ++r) {
      addRun(s, runs.begin[r], runs.end[r], b.sums[runs.cell[r]]);
    }
    // The stripe's last cell is the next one's previous (an outside point's too: kOutside).
    s.cx[0] = s.cx[n], s.cy[0] = s.cy[n], s.cz[0] = s.cz[n];
  }
  return fits;
}

// Empties b for about as many cells as it held (its table and arrays kept).
void clearBins(Bins& b) {
  b.grid.clear(std::max<std::size_t>(b.grid.size(), 64));
  b.sums.clear();
}

// The per-chunk bins and the merge's id maps, kept from frame to frame (no tables built and
// grown again every frame).
struct ChunkBins {
  std::vector<Bins> bins;
  std::vector<std::vector<std::uint32_t>> remap;
};

// Bins the points of every chunk (binRange), then merges the chunks' cells in chunk order into
// out; cell_of[i] is then point i's cell in out.
void binPoints(const PointCloud& cloud, const Normals& normals, const Lattice& lat,
               const PointChunks& chunks, double radius_m, std::uint32_t* cell_of, Bins& out) {
  const auto n_chunks = static_cast<std::ptrdiff_t>(chunks.count);
  static thread_local ChunkBins kept;
  ChunkBins& cb = kept;  // (the calling thread's, named in the regions)
  if (cb.bins.size() < chunks.count) cb.bins.resize(chunks.count), cb.remap.resize(chunks.count);
  int all_fit = 1;
  // A dynamic schedule over the chunks (equal numbers of finite points): a chunk's cost still
  // varies with its points' runs (far points cross cells more often), and with static shares
  // of them the second thread waited for the first on most frames; the merge below runs in
  // chunk order, so the result does not depend on who took which chunk. (The other stages
  // keep static shares, so that a point's data mostly stay in one core's cache: see
  // copyCloud.)
#pragma omp parallel for schedule(dynamic, 1) reduction(& : all_fit)
  for (std::ptrdiff_t c = 0; c < n_chunks; ++c) {
    const auto cu = static_cast<std::size_t>(c);
    static thread_local StripeBuffers stripes;  // (this thread's: named inside the region)
    clearBins(cb.bins[cu]);
    all_fit &= binRange(cloud, normals, lat, chunks.begin(cu), chunks.end(cu), cb.bins[cu],
                        cell_of, stripes)
                   ? 1
                   : 0;
  }
  if (!all_fit) {
    throw std::invalid_argument(
        "UpdParams.radius_m = " + std::to_string(radius_m) +
        ": the cloud spans more than 2^20 fast-path lattice cells along an axis; use a "
        "range cut-off, a larger radius or fewer fast_cells_per_radius");
  }
  // The first chunk's cells first, in its order: their ids in out are the chunk's own, and
  // their sums its sums as they are.
  clearBins(out);
  for (std::size_t c = 0; c < chunks.count; ++c) {
    const Bins& b = cb.bins[c];
    std::vector<std::uint32_t>& remap = cb.remap[c];
    remap.resize(b.sums.size());
    for (std::size_t j = 0; j < b.sums.size(); ++j) {
      const std::int32_t* xyz = b.grid.xyz(j);
      const std::uint32_t id = out.cellOf(xyz[0], xyz[1], xyz[2]);
      if (c == 0) {
        out.sums[id] = b.sums[j];
      } else {
        out.sums[id].add(b.sums[j]);
      }
      remap[j] = id;
    }
  }
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t c = 0; c < n_chunks; ++c) {
    if (c == 0) continue;  // (from 0: the same shares as the binning)
    const auto cu = static_cast<std::size_t>(c);
    const std::uint32_t* remap = cb.remap[cu].data();
    for (std::size_t i = chunks.begin(cu); i < chunks.end(cu); ++i) {
      if (cell_of[i] != kNoIndex) cell_of[i] = remap[cell_of[i]];
    }
  }
}

// The occupied cells of lattice lat and the points with a valid normal in them (binRange's
// cells and the sum of their counts), over every step-th stripe of kStripe points from first:
// step 1 counts every point; a larger step gives a lower bound of the cells.
struct CellCount {
  std::size_t cells = 0;
  double valid = 0;
};

// A stripe's cells as countCells reads them: each point's cell (cx = kOutside as in toLattice)
// and whether it differs from the point before's (prev: the cell before the stripe).
struct CellStripe {
  float cx[kStripe + 1], cy[kStripe + 1], cz[kStripe + 1];
  std::uint8_t change[kStripe];
};

UPD_VECTOR_CLONES
std::uint32_t cellChanges(const float* __restrict x, const float* __restrict y,
                          const float* __restrict z, const float* __restrict nx,
                          const Lattice& lat, std::size_t n, CellStripe& __restrict s) {
  std::uint32_t valid = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const float gx = lat.gx(x[j]), gy = lat.gy(y[j]), gz = lat.gz(z[j]);
    const bool inside = inLattice(gx, gy, gz);  // toLattice's test and floors: its cells
    s.cx[j + 1] = inside ? std::floor(gx) : kOutside;
    s.cy[j + 1] = std::floor(gy), s.cz[j + 1] = std::floor(gz);
    valid += static_cast<std::uint32_t>(inside) & static_cast<std::uint32_t>(nx[j] == nx[j]);
  }
  for (std::size_t j = 0; j < n; ++j) {
    const bool same = (static_cast<int>(s.cx[j + 1] == s.cx[j]) &
                       static_cast<int>(s.cy[j + 1] == s.cy[j]) &
                       static_cast<int>(s.cz[j + 1] == s.cz[j])) != 0;
    s.change[j] = static_cast<std::uint8_t>(static_cast<int>(!same) &
                                            static_cast<int>(s.cx[j + 1] != kOutside));
  }
  return valid;
}

// The cells and valid points of the sampled stripes [j0, j1) (stripe j starts at first +
// j * step * kStripe) into grid; returns the valid points.
std::size_t countStripes(const PointCloud& cloud, const Normals& normals, const Lattice& lat,
                         std::size_t first, std::size_t step, std::size_t j0, std::size_t j1,
                         CellGrid& grid) {
  CellStripe s;  // (on the stack: a thread_local's address costs a call at each use here)
  std::size_t valid = 0;
  s.cx[0] = kOutside, s.cy[0] = s.cz[0] = 0.f;
  const std::size_t n_pts = cloud.size();
  for (std::size_t j = j0; j < j1; ++j) {
    const std::size_t s0 = first + j * step * kStripe;
    const std::size_t n = std::min(kStripe, n_pts - s0);
    valid += cellChanges(&cloud.x[s0], &cloud.y[s0], &cloud.z[s0], &normals.nx[s0], lat, n, s);
    for (std::size_t i = 0; i < n; ++i) {
      if (!s.change[i]) continue;
      grid.insert(static_cast<std::int32_t>(s.cx[i + 1]), static_cast<std::int32_t>(s.cy[i + 1]),
                  static_cast<std::int32_t>(s.cz[i + 1]));
    }
    // The stripe's last cell is the next one's previous (an outside point's too: kOutside).
    s.cx[0] = s.cx[n], s.cy[0] = s.cy[n], s.cz[0] = s.cz[n];
  }
  return valid;
}

// The team's threads count runs of the sampled stripes, taken in turn (the image's rows differ
// in cost: the far ones change cells more often), each into a grid of its own; the cells are
// then their union (a few thousand: the points are what costs). The count and the cells do not
// depend on how the stripes are shared.
CellCount countCells(const PointCloud& cloud, const Normals& normals, const Lattice& lat,
                     std::size_t first, std::size_t step) {
  const std::size_t n_stripes = (cloud.size() - first + step * kStripe - 1) / (step * kStripe);
  const auto most = static_cast<std::size_t>(openmp::maxThreads());
  std::vector<CellGrid> grids(most);
  // (About 16 runs a thread; a run's first stripe starts from no cell: one insertion more.)
  const std::size_t per_run = std::max<std::size_t>(1, n_stripes / (16 * most));
  const auto n_runs = static_cast<std::ptrdiff_t>((n_stripes + per_run - 1) / per_run);
  std::size_t valid = 0;
#pragma omp parallel reduction(+ : valid)
  {
    const auto me = static_cast<std::size_t>(openmp::threadIndex());
#pragma omp for schedule(dynamic, 1)
    for (std::ptrdiff_t r = 0; r < n_runs; ++r) {
      const std::size_t j0 = static_cast<std::size_t>(r) * per_run;
      valid += countStripes(cloud, normals, lat, first, step, j0,
                            std::min(n_stripes, j0 + per_run), grids[me]);
    }
  }
  CellGrid& all = grids[0];
  for (std::size_t t = 1; t < grids.size(); ++t) {
    for (std::size_t c = 0; c < grids[t].size(); ++c) {
      const std::int32_t* xyz = grids[t].xyz(c);
      all.insert(xyz[0], xyz[1], xyz[2]);
    }
  }
  CellCount count;
  count.cells = all.size();
  count.valid = static_cast<double>(valid);
  return count;
}

// The values of x[0, n) that are not NaN (the points with a normal), in a vector loop.
UPD_VECTOR_CLONES
std::size_t countNumbers(const float* __restrict x, std::size_t n) {
  std::uint32_t k = 0;
  for (std::size_t i = 0; i < n; ++i) k += static_cast<std::uint32_t>(x[i] == x[i]);
  return k;
}

// Every 4th stripe: on a frame far from the refinement budget (most cells seen by a quarter of
// the image) the lower bound settles it for ~a tenth of a count of every point.
constexpr std::size_t kSampleStep = 4;

// The lattice's cells per d_m under fast_cells_per_point: finerCellsPerRadius on the cells and
// valid points binning at f.m would give, found without binning. The cells of a sample and
// the points with any valid normal bound the rule from the side of no refinement (it refines
// less with more cells or fewer points): where they already keep f.m, so does every point's
// count; otherwise every point is counted.
int latticeCells(const FastFrame& f) {
  const double cells_per_point = f.params.fast_cells_per_point;
  const std::size_t first = f.chunks.first_finite, n_pts = f.cloud.size();
  std::size_t with_normal = 0;
  constexpr std::size_t kShare = 1 << 14;
  const auto n_shares = static_cast<std::ptrdiff_t>((n_pts - first + kShare - 1) / kShare);
#pragma omp parallel for schedule(static) reduction(+ : with_normal)
  for (std::ptrdiff_t k = 0; k < n_shares; ++k) {
    const std::size_t b = first + static_cast<std::size_t>(k) * kShare;
    with_normal += countNumbers(f.normals.nx.data() + b, std::min(kShare, n_pts - b));
  }
  const CellCount sample = countCells(f.cloud, f.normals, f.lat, first, kSampleStep);
  if (finerCellsPerRadius(f.m, sample.cells, static_cast<double>(with_normal),
                          cells_per_point) == f.m) {
    return f.m;
  }
  const CellCount all = countCells(f.cloud, f.normals, f.lat, first, 1);
  return finerCellsPerRadius(f.m, all.cells, all.valid, cells_per_point);
}

}  // namespace

void binFrame(FastFrame& f, Bins& out) {
  const double radius_m = f.params.radius_m;
  // A finer lattice where the points are dense (fast_cells_per_point): the node work grows
  // with the cells, so it stays a fixed share of the per-point work. Decided by counting the
  // cells, so that the points are binned once.
  if (f.params.fast_cells_per_point > 0) {
    const int finer = latticeCells(f);
    if (finer > f.m) {
      f.m = finer;
      f.lat.inv_cell = static_cast<float>(f.m / radius_m);
    }
  }
  binPoints(f.cloud, f.normals, f.lat, f.chunks, radius_m, f.cell_of, out);
}

}  // namespace upd::core::detail
