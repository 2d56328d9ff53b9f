// The fast UPD's first stage: the points binned into the lattice's cells, with per cell the
// sums the ball sums read (CellSums), in fixed chunks merged in chunk order. binRange is
// binCells (fast_cell_map.h) specialized for the lattice: the cell coordinates of a stripe of
// points in one vector loop, and the sums of a run of points in one cell added at once.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "fast_upd_internal.h"

namespace upd::core::detail {

namespace {

// A stripe of points in lattice terms, the first pass of binRange: each point's cell (cx, cy,
// cz: integers as floats, exact below 2^24; cx = kOutside for a point that is not finite or
// lies beyond the key range) and its contribution to the CellSums of its cell, in their order
// (count, normal, position inside the cell, its products), zeros where the normal is invalid.
constexpr float kOutside = -2.f * kMaxCoord;
constexpr std::size_t kStripe = 256;
struct Stripe {
  float cx[kStripe], cy[kStripe], cz[kStripe];
  float term[13][kStripe];  // the 13 of CellSums
};

// A point's lattice coordinates within the key range; NaN and infinity fail the test too. (&
// rather than &&, on ints for clang's -Wbitwise-instead-of-logical: no branch, so the loops
// that call it vectorize.)
inline bool inLattice(float gx, float gy, float gz) {
  return (static_cast<int>(std::fabs(gx) < kMaxCoord) & static_cast<int>(std::fabs(gy) < kMaxCoord) &
          static_cast<int>(std::fabs(gz) < kMaxCoord)) != 0;
}

UPD_VECTOR_CLONES
void toLattice(const float* __restrict x, const float* __restrict y, const float* __restrict z,
               const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
               const Lattice& lat, std::size_t n, Stripe& __restrict s) {
  for (std::size_t j = 0; j < n; ++j) {
    const float gx = lat.gx(x[j]), gy = lat.gy(y[j]), gz = lat.gz(z[j]);
    // (Floors as floats, everything loaded and computed before it is selected: no branch, so
    // the loop vectorizes.)
    const bool inside = inLattice(gx, gy, gz);
    const float fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
    const float ax = nx[j], ay = ny[j], az = nz[j];
    const bool valid = ax == ax;
    const float px = valid ? gx - fx : 0.f, py = valid ? gy - fy : 0.f, pz = valid ? gz - fz : 0.f;
    s.cx[j] = inside ? fx : kOutside;
    s.cy[j] = fy, s.cz[j] = fz;
    auto& t = s.term;
    t[0][j] = valid ? 1.f : 0.f;
    t[1][j] = valid ? ax : 0.f, t[2][j] = valid ? ay : 0.f, t[3][j] = valid ? az : 0.f;
    t[4][j] = px, t[5][j] = py, t[6][j] = pz;
    t[7][j] = px * px, t[8][j] = px * py, t[9][j] = px * pz, t[10][j] = py * py;
    t[11][j] = py * pz, t[12][j] = pz * pz;
  }
}

// Bins points [begin, end) into b, writing each point's cell (local to b) into cell_of.
// Consecutive points (image rows, scan lines) mostly share a cell: the sums of such a run are
// kept in one vector register (a point adds its 13 terms at once) and the hash map is
// consulted once per change of cell. Returns false when a point lies beyond the lattice's key
// range (it is left out).
UPD_VECTOR_CLONES
bool binRange(const PointCloud& cloud, const Normals& normals, const Lattice& lat,
              std::size_t begin, std::size_t end, Bins& b, std::uint32_t* cell_of) {
  float lx = kOutside, ly = 0, lz = 0;  // the cell of the run
  std::uint32_t last = kNoIndex;
  bool fits = true;
  float r0 = 0, r1 = 0, r2 = 0, r3 = 0, r4 = 0, r5 = 0, r6 = 0, r7 = 0, r8 = 0, r9 = 0, r10 = 0,
        r11 = 0, r12 = 0;
  const auto flush = [&] {
    if (last != kNoIndex && r0 > 0.f) {
      b.sums[last].add({r0, r1, r2, r3, r4, r5, r6, r7, r8, r9, r10, r11, r12});
    }
    r0 = r1 = r2 = r3 = r4 = r5 = r6 = r7 = r8 = r9 = r10 = r11 = r12 = 0.f;
  };
  static thread_local Stripe s;
  for (std::size_t s0 = begin; s0 < end; s0 += kStripe) {
    const std::size_t n = std::min(kStripe, end - s0);
    toLattice(&cloud.x[s0], &cloud.y[s0], &cloud.z[s0], &normals.nx[s0], &normals.ny[s0],
              &normals.nz[s0], lat, n, s);
    for (std::size_t j = 0; j < n; ++j) {
      const std::size_t i = s0 + j;
      if (s.cx[j] == kOutside) {
        if (std::isfinite(cloud.x[i]) && std::isfinite(cloud.y[i]) && std::isfinite(cloud.z[i])) {
          fits = false;
        }
        cell_of[i] = kNoIndex;
        continue;
      }
      if (s.cx[j] != lx || s.cy[j] != ly || s.cz[j] != lz) {
        flush();
        lx = s.cx[j], ly = s.cy[j], lz = s.cz[j];
        last = b.cellOf(static_cast<std::int32_t>(lx), static_cast<std::int32_t>(ly),
                        static_cast<std::int32_t>(lz));
      }
      cell_of[i] = last;
      const auto& t = s.term;
      r0 += t[0][j], r1 += t[1][j], r2 += t[2][j], r3 += t[3][j], r4 += t[4][j];
      r5 += t[5][j], r6 += t[6][j], r7 += t[7][j], r8 += t[8][j], r9 += t[9][j];
      r10 += t[10][j], r11 += t[11][j], r12 += t[12][j];
    }
  }
  flush();
  return fits;
}

// Bins the points of every chunk (binRange), then merges the chunks' cells in chunk order;
// cell_of[i] is then point i's cell in the result.
Bins binPoints(const PointCloud& cloud, const Normals& normals, const Lattice& lat,
               const PointChunks& chunks, double radius_m, std::uint32_t* cell_of) {
  const auto n_chunks = static_cast<std::ptrdiff_t>(chunks.count);
  std::vector<Bins> chunk_bins(chunks.count);
  int all_fit = 1;
  // Static schedules here and in the later stages: every stage of a frame deals the points out
  // to the threads in the same contiguous shares, so that a point's data stay in one core's
  // cache (see copyCloud). Dynamic schedules scattered them, and on a two-vCPU VM a line the
  // other core has read costs twice as much to write again.
#pragma omp parallel for schedule(static) reduction(& : all_fit)
  for (std::ptrdiff_t c = 0; c < n_chunks; ++c) {
    const auto cu = static_cast<std::size_t>(c);
    all_fit &=
        binRange(cloud, normals, lat, chunks.begin(cu), chunks.end(cu), chunk_bins[cu], cell_of)
            ? 1
            : 0;
  }
  if (!all_fit) {
    throw std::invalid_argument(
        "UpdParams.radius_m = " + std::to_string(radius_m) +
        ": the cloud spans more than 2^20 fast-path lattice cells along an axis; use a "
        "range cut-off, a larger radius or fewer fast_cells_per_radius");
  }
  Bins bins = std::move(chunk_bins[0]);
  std::vector<std::vector<std::uint32_t>> remap(chunks.count);
  for (std::size_t c = 1; c < chunks.count; ++c) {
    const Bins& cb = chunk_bins[c];
    remap[c].resize(cb.sums.size());
    for (std::size_t j = 0; j < cb.sums.size(); ++j) {
      const std::int32_t* xyz = cb.grid.xyz(j);
      const std::uint32_t id = bins.cellOf(xyz[0], xyz[1], xyz[2]);
      bins.sums[id].add(cb.sums[j]);
      remap[c][j] = id;
    }
  }
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t c = 0; c < n_chunks; ++c) {
    if (c == 0) continue;  // (from 0: the same shares as the binning)
    const auto cu = static_cast<std::size_t>(c);
    for (std::size_t i = chunks.begin(cu); i < chunks.end(cu); ++i) {
      if (cell_of[i] != kNoIndex) cell_of[i] = remap[cu][cell_of[i]];
    }
  }
  return bins;
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

CellCount countCells(const PointCloud& cloud, const Normals& normals, const Lattice& lat,
                     std::size_t first, std::size_t step) {
  static thread_local CellStripe s;
  CellGrid grid;
  CellCount count;
  std::size_t valid = 0;
  s.cx[0] = kOutside, s.cy[0] = s.cz[0] = 0.f;
  const std::size_t n_pts = cloud.size();
  for (std::size_t s0 = first; s0 < n_pts; s0 += step * kStripe) {
    const std::size_t n = std::min(kStripe, n_pts - s0);
    valid += cellChanges(&cloud.x[s0], &cloud.y[s0], &cloud.z[s0], &normals.nx[s0], lat, n, s);
    for (std::size_t j = 0; j < n; ++j) {
      if (!s.change[j]) continue;
      bool inserted = false;
      grid.insert(static_cast<std::int32_t>(s.cx[j + 1]), static_cast<std::int32_t>(s.cy[j + 1]),
                  static_cast<std::int32_t>(s.cz[j + 1]), inserted);
    }
    // The stripe's last cell is the next one's previous (an outside point's too: kOutside).
    s.cx[0] = s.cx[n], s.cy[0] = s.cy[n], s.cz[0] = s.cz[n];
  }
  count.cells = grid.size();
  count.valid = static_cast<double>(valid);
  return count;
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
  const std::size_t first = f.chunks.first, n_pts = f.cloud.size();
  std::size_t with_normal = 0;
  const float* nx = f.normals.nx.data();
  for (std::size_t i = first; i < n_pts; ++i) with_normal += nx[i] == nx[i] ? 1 : 0;
  const CellCount sample = countCells(f.cloud, f.normals, f.lat, first, kSampleStep);
  if (finerCellsPerRadius(f.m, sample.cells, static_cast<double>(with_normal),
                          cells_per_point) == f.m) {
    return f.m;
  }
  const CellCount all = countCells(f.cloud, f.normals, f.lat, first, 1);
  return finerCellsPerRadius(f.m, all.cells, all.valid, cells_per_point);
}

}  // namespace

Bins binFrame(FastFrame& f) {
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
  return binPoints(f.cloud, f.normals, f.lat, f.chunks, radius_m, f.cell_of);
}

}  // namespace upd::core::detail
