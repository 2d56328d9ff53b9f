// The fast UPD's exact band (UpdParams::fast_exact_band): exact sums for the points whose zeta
// lies within the band of the label threshold, so that their label is the exact path's. A cell
// wholly inside the ball adds its sums, one wholly outside nothing, and the points of a cell
// the sphere cuts are tested one by one.
#include <algorithm>
#include <cmath>

#include "fast_upd_internal.h"

namespace upd::core::detail {

namespace {

// The cells within reach of a ball around any point of one cell, structure of arrays padded
// with empty far-away cells to a multiple of kLanes: lower corner relative to that cell (cell
// units), valid-normal count and normal sum, and the cell's index.
struct ExactCandidates {
  std::vector<float> lx, ly, lz, count, nx, ny, nz;
  std::vector<std::uint32_t> cell;
  void clear() {
    for (auto* v : {&lx, &ly, &lz, &count, &nx, &ny, &nz}) v->clear();
    cell.clear();
  }
  void append(float x, float y, float z, const CellSums& s, std::uint32_t c) {
    lx.push_back(x), ly.push_back(y), lz.push_back(z);
    count.push_back(s.count), nx.push_back(s.nx), ny.push_back(s.ny), nz.push_back(s.nz);
    cell.push_back(c);
  }
  void pad() {
    while (lx.size() % kLanes != 0) append(1e6f, 1e6f, 1e6f, CellSums{}, kNoIndex);
  }
  std::size_t size() const { return lx.size(); }
  // The cells of `cells` within m cells (box to box) of cell `own` (cell_xyz[3 * own]), padded:
  // every cell that a ball of radius m around one of own's points can reach.
  void gather(const std::vector<std::uint32_t>& cells, std::size_t own, std::int32_t m,
              const std::int32_t* cell_xyz, const CellSums* sums) {
    clear();
    for (const std::uint32_t j : cells) {
      std::int32_t d[3], gap2 = 0;
      for (int a = 0; a < 3; ++a) {
        d[a] = cell_xyz[3 * j + a] - cell_xyz[3 * own + a];
        const std::int32_t gap = std::max(0, std::abs(d[a]) - 1);
        gap2 += gap * gap;
      }
      if (gap2 > m * m) continue;
      append(static_cast<float>(d[0]), static_cast<float>(d[1]), static_cast<float>(d[2]), sums[j],
             j);
    }
    pad();
  }
};

// Adds the lane sums of the four accumulators (r_x, r_y, r_z, k) to acc.
inline void addLanes(const float (&a)[4][kLanes], float (&acc)[4]) {
  for (int v = 0; v < 4; ++v) {
    float s = 0.f;
    for (int l = 0; l < kLanes; ++l) s += a[v][l];
    acc[v] += s;
  }
}

// Sums (r, k) over the candidate cells wholly inside the ball of radius m cells around X (cell
// units, relative to the candidates' origin) into acc, and marks in cut the cells the sphere
// cuts (their points are summed one by one). in2 and out2 bracket m^2 by a rounding margin, so
// that a cell is taken whole or skipped only when every point of it certainly is in or out.
UPD_VECTOR_CLONES
void sumWholeCells(const ExactCandidates& c, float X, float Y, float Z, float in2, float out2,
                   float (&acc)[4], float* __restrict cut) {
  float a[4][kLanes] = {};
  const std::size_t n = c.size();
  const float* __restrict lx = c.lx.data();
  const float* __restrict ly = c.ly.data();
  const float* __restrict lz = c.lz.data();
  const float* __restrict cnt = c.count.data();
  const float* __restrict nx = c.nx.data();
  const float* __restrict ny = c.ny.data();
  const float* __restrict nz = c.nz.data();
  for (std::size_t j0 = 0; j0 < n; j0 += kLanes) {
    for (int l = 0; l < kLanes; ++l) {
      const std::size_t j = j0 + l;
      float near2, far2;
      boxDistances2(lx[j] - X, ly[j] - Y, lz[j] - Z, near2, far2);
      const float inside = far2 <= in2 ? 1.f : 0.f;
      cut[j] = (1.f - inside) * (near2 <= out2 ? 1.f : 0.f) * (cnt[j] > 0.f ? 1.f : 0.f);
      a[0][l] += inside * nx[j];
      a[1][l] += inside * ny[j];
      a[2][l] += inside * nz[j];
      a[3][l] += inside * cnt[j];
    }
  }
  addLanes(a, acc);
}

// Adds the normals of the points of cells [0, n) (their ranges [begin[c], end[c]) in p) within
// distance^2 r2 of (X, Y, Z) and their count to acc: the exact path's test, |p - q|^2 <= r^2.
// (Float rounding may put a point within ~1e-7 r of the sphere on the other side than the k-d
// tree does.) A range is read a vector of points at a time, lanes past its end masked off (p is
// padded by kLanes): the lanes are reduced once, not once per cell.
UPD_VECTOR_CLONES
void sumPointsWithin(const CellPoints& p, const std::uint32_t* begin, const std::uint32_t* end,
                     std::size_t n, float X, float Y, float Z, float r2, float (&acc)[4]) {
  float a[4][kLanes] = {};
  const float* __restrict x = p.x.data();
  const float* __restrict y = p.y.data();
  const float* __restrict z = p.z.data();
  const float* __restrict nx = p.nx.data();
  const float* __restrict ny = p.ny.data();
  const float* __restrict nz = p.nz.data();
  for (std::size_t c = 0; c < n; ++c) {
    const std::size_t b = begin[c], e = end[c];
    for (std::size_t j0 = b; j0 < e; j0 += kLanes) {
      // Lanes l < e - j0 are in the range.
      const auto valid = static_cast<std::ptrdiff_t>(e - j0);
      for (int l = 0; l < kLanes; ++l) {
        const std::size_t j = j0 + static_cast<std::size_t>(l);
        const float dx = x[j] - X, dy = y[j] - Y, dz = z[j] - Z;
        const float w = ((dx * dx + dy * dy + dz * dz <= r2) & (l < valid)) ? 1.f : 0.f;
        a[0][l] += w * nx[j];
        a[1][l] += w * ny[j];
        a[2][l] += w * nz[j];
        a[3][l] += w;
      }
    }
  }
  addLanes(a, acc);
}

// Scratch of exactBallSums, kept by each thread across its queries.
struct ExactScratch {
  std::vector<float> cut;
  std::vector<std::uint32_t> cut_begin, cut_end;
};

// Eq. 6 and k at a point over its true neighbourhood: the candidate cells wholly inside the
// ball add their sums, the points of the cells the sphere cuts are tested one by one. q_cell is
// the point in cell units relative to the candidates' origin, q its position relative to the
// lattice origin (world units); in2 and out2 bracket m^2 (sumWholeCells), r2 = d_m^2.
void exactBallSums(const ExactCandidates& cand, const CellPoints& pts, const float (&q_cell)[3],
                   const float (&q)[3], float in2, float out2, float r2, ExactScratch& s,
                   float (&acc)[4]) {
  s.cut.resize(cand.size());
  s.cut_begin.resize(cand.size()), s.cut_end.resize(cand.size());
  acc[0] = acc[1] = acc[2] = acc[3] = 0.f;
  sumWholeCells(cand, q_cell[0], q_cell[1], q_cell[2], in2, out2, acc, s.cut.data());
  // The cut cells' point ranges, listed without a branch per candidate.
  std::size_t n_cut = 0;
  for (std::size_t j = 0; j < cand.size(); ++j) {
    const std::uint32_t cell = cand.cell[j];
    s.cut_begin[n_cut] = cell == kNoIndex ? 0 : pts.start[cell];
    s.cut_end[n_cut] = cell == kNoIndex ? 0 : pts.start[cell + 1];
    n_cut += s.cut[j] != 0.f ? 1 : 0;
  }
  sumPointsWithin(pts, s.cut_begin.data(), s.cut_end.data(), n_cut, q[0], q[1], q[2], r2, acc);
}

// The points whose zeta lies in (lo, hi), per chunk in point order, and per chunk and cell the
// points with a valid normal (count[chunk * n_cells + cell]), in the binning's shares.
void chooseBandPoints(const FastFrame& f, std::size_t n_cells, float lo, float hi,
                      const UpdResult& out, std::vector<std::vector<std::uint32_t>>& chosen,
                      std::vector<std::uint32_t>& count) {
  const PointChunks& chunks = f.chunks;
  chosen.assign(chunks.count, {});
  count.assign(chunks.count * n_cells, 0);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(chunks.count); ++c) {
    const auto cu = static_cast<std::size_t>(c);
    std::uint32_t* n = &count[cu * n_cells];
    for (std::size_t i = chunks.begin(cu); i < chunks.end(cu); ++i) {
      const std::uint32_t cell = f.cell_of[i];
      if (cell == kNoIndex) continue;
      if (out.zeta[i] > lo && out.zeta[i] < hi) chosen[cu].push_back(static_cast<std::uint32_t>(i));
      if (f.normals.isValid(i)) ++n[cell];
    }
  }
}

// Counting sort of the valid-normal points by cell into pts, chunk by chunk (count from
// chooseBandPoints, then each chunk's first slot per cell): the same order for any number of
// threads.
void sortValidPointsByCell(const FastFrame& f, std::size_t n_cells,
                           std::vector<std::uint32_t>& count, CellPoints& pts) {
  const PointChunks& chunks = f.chunks;
  pts.start.assign(n_cells + 1, 0);
  for (std::size_t cell = 0; cell < n_cells; ++cell) {
    std::uint32_t at = pts.start[cell];
    for (std::size_t c = 0; c < chunks.count; ++c) {
      const std::uint32_t k = count[c * n_cells + cell];
      count[c * n_cells + cell] = at;  // now the chunk's first slot in the cell
      at += k;
    }
    pts.start[cell + 1] = at;
  }
  const std::size_t n_valid = pts.start[n_cells];
  // (kLanes more: sumPointsWithin reads whole vectors, masking the lanes past a range.)
  for (auto* v : {&pts.x, &pts.y, &pts.z, &pts.nx, &pts.ny, &pts.nz}) {
    v->assign(n_valid + kLanes, 0.f);
  }
  const PointCloud& cloud = f.cloud;
  const Normals& normals = f.normals;
  const Lattice& lat = f.lat;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(chunks.count); ++c) {
    const auto cu = static_cast<std::size_t>(c);
    std::uint32_t* slot = &count[cu * n_cells];
    for (std::size_t i = chunks.begin(cu); i < chunks.end(cu); ++i) {
      const std::uint32_t cell = f.cell_of[i];
      if (cell == kNoIndex || !normals.isValid(i)) continue;
      const std::uint32_t j = slot[cell]++;
      pts.x[j] = cloud.x[i] - lat.rx, pts.y[j] = cloud.y[i] - lat.ry;
      pts.z[j] = cloud.z[i] - lat.rz;
      pts.nx[j] = normals.nx[i], pts.ny[j] = normals.ny[i], pts.nz[j] = normals.nz[i];
    }
  }
}

// Exact sums for the points chosen[from, to) of cell c, whose candidates cand holds; returns
// the points left unscored.
std::size_t scoreCellExactly(const FastFrame& f, const Bins& bins, const CellPoints& pts,
                             std::size_t c, const std::uint32_t* chosen, std::size_t from,
                             std::size_t to, const ExactCandidates& cand, ExactScratch& scratch,
                             UpdResult& out) {
  const float mf = static_cast<float>(f.m);
  const float m2 = mf * mf;
  const float in2 = m2 * (1.f - 1e-4f), out2 = m2 * (1.f + 1e-4f);
  const auto radius = static_cast<float>(f.params.radius_m);
  const float r2 = radius * radius;
  const auto min_k = static_cast<std::uint32_t>(f.params.min_neighbors);
  const Lattice& lat = f.lat;
  const PointCloud& cloud = f.cloud;
  const std::int32_t* own = bins.grid.xyz(c);
  std::size_t invalid = 0;
  for (std::size_t q = from; q < to; ++q) {
    const std::uint32_t i = chosen[q];
    const float q_cell[3] = {lat.gx(cloud.x[i]) - static_cast<float>(own[0]),
                             lat.gy(cloud.y[i]) - static_cast<float>(own[1]),
                             lat.gz(cloud.z[i]) - static_cast<float>(own[2])};
    const float q_world[3] = {cloud.x[i] - lat.rx, cloud.y[i] - lat.ry, cloud.z[i] - lat.rz};
    float acc[4];
    exactBallSums(cand, pts, q_cell, q_world, in2, out2, r2, scratch, acc);
    const auto k = static_cast<std::uint32_t>(acc[3] + 0.5f);
    if (k < min_k) {
      setUnscored(out, i);
      ++invalid;
      continue;
    }
    out.rx[i] = acc[0], out.ry[i] = acc[1], out.rz[i] = acc[2];
    const double r_norm =
        std::sqrt(double(acc[0]) * acc[0] + double(acc[1]) * acc[1] + double(acc[2]) * acc[2]);
    out.zeta[i] = static_cast<float>(r_norm / k);
    out.k[i] = k;
  }
  return invalid;
}

}  // namespace

std::size_t scoreExactBand(const FastFrame& f, const LatticeIndex& index, const Bins& bins,
                           double zeta_threshold, CellPoints& pts, UpdResult& out,
                           std::size_t& invalid) {
  const auto lo = static_cast<float>(zeta_threshold - f.params.fast_exact_band);
  const auto hi = static_cast<float>(zeta_threshold + f.params.fast_exact_band);
  const std::size_t n_cells = bins.sums.size();
  std::vector<std::vector<std::uint32_t>> chosen;
  std::vector<std::uint32_t> count;
  chooseBandPoints(f, n_cells, lo, hi, out, chosen, count);
  std::vector<std::uint32_t> all;  // the chosen points, in point order
  for (const auto& v : chosen) all.insert(all.end(), v.begin(), v.end());
  if (all.empty()) return 0;
  sortValidPointsByCell(f, n_cells, count, pts);
  // The chosen points grouped by cell: each cell's candidates are gathered once.
  CellLists by_cell;
  listByCell(
      all.size(), n_cells, [&](std::size_t q) { return f.cell_of[all[q]]; }, by_cell);
  for (std::uint32_t& q : by_cell.order) q = all[q];
  std::size_t newly_invalid = 0;
#pragma omp parallel reduction(+ : newly_invalid)
  {
    ExactCandidates cand;
    std::vector<std::uint32_t> cells;
    ExactScratch scratch;
#pragma omp for schedule(dynamic, 2)
    for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
      const auto c = static_cast<std::size_t>(cc);
      if (by_cell.empty(c)) continue;
      index.around(index.cell_block[c], bins.sums, cells);
      cand.gather(cells, c, f.m, bins.grid.coords().data(), bins.sums.data());
      newly_invalid += scoreCellExactly(f, bins, pts, c, by_cell.order.data(), by_cell.start[c],
                                        by_cell.start[c + 1], cand, scratch, out);
    }
  }
  invalid += newly_invalid;
  return all.size();
}

}  // namespace upd::core::detail
