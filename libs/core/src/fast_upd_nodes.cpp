// The fast UPD's lattice stages: the nodes (cell corners) and blocks of the occupied cells, the
// ball sums at every node (eq. 6 and k over the cells, sumAtNode), and the cells whose nodes
// disagree on zeta, whose points are summed at their own position instead of interpolated.
#include <algorithm>
#include <array>
#include <cmath>

#include "fast_upd_internal.h"
#include "upd/core/openmp.h"
#include "upd/core/vector_clones.h"

namespace upd::core::detail {

namespace {

// The candidate cells of a group of nodes, structure of arrays padded with empty cells to a
// multiple of kLanes, positions relative to the group's block origin in cell units.
struct Candidates {
  enum Field {
    kLx,
    kLy,
    kLz,
    kMx,
    kMy,
    kMz,
    kCxx,
    kCxy,
    kCxz,
    kCyy,
    kCyz,
    kCzz,
    kCount,
    kNx,
    kNy,
    kNz,
    kFields
  };
  // Field k of row j at buf[k * cap + j]: lower corner, centroid, covariance, sums.
  std::vector<float> buf;
  std::size_t cap = 0, n = 0;

  const float* operator[](Field k) const { return buf.data() + k * cap; }
  std::size_t size() const { return n; }
  // Empties the rows, with room for max_rows and the padding.
  void reset(std::size_t max_rows) {
    cap = (max_rows + 2 * kLanes - 1) / kLanes * kLanes;
    if (buf.size() < kFields * cap) buf.resize(kFields * cap);
    n = 0;
  }
  void append(const float (&row)[kFields]) {
    for (int k = 0; k < kFields; ++k) buf[k * cap + n] = row[k];
    ++n;
  }
  // Empty cells (count 0) up to a multiple of kLanes.
  void pad() {
    const float zero[kFields] = {};
    while (n % kLanes != 0) append(zero);
  }
  // The row of cell c, lower corner relative to origin.
  static void rowOf(std::uint32_t c, const std::int32_t* cell_xyz, const CellRow* rows,
                    const std::int32_t origin[3], float (&row)[kFields]) {
    for (int a = 0; a < 3; ++a) {
      const auto l = static_cast<float>(cell_xyz[3 * c + a] - origin[a]);
      row[kLx + a] = l;
      row[kMx + a] = l + rows[c].f[CellRow::kMx + a];
    }
    for (int k = CellRow::kCxx; k < CellRow::kFields; ++k) {
      row[kCxx + k - CellRow::kCxx] = rows[c].f[k];
    }
  }
  // Rows for cells[0, m), padded.
  void fill(std::size_t m, const std::uint32_t* cells, const std::int32_t* cell_xyz,
            const CellRow* rows, const std::int32_t origin[3]) {
    reset(m);
    float row[kFields];
    for (std::size_t j = 0; j < m; ++j) {
      rowOf(cells[j], cell_xyz, rows, origin, row);
      append(row);
    }
    pad();
  }
};

// Eq. 6 and k at one node X (block-relative, cell units) for a ball of radius m cells, with
// their gradients. A cell wholly inside adds its sums, one wholly outside nothing; a cell the
// sphere cuts adds the fraction of its points on the inner side, from the spread of its points
// along the direction u from X to its centroid (uniform with the cell's variance sigma^2 along
// u: frac = 1/2 + t / (2 sqrt(3) sigma), t the centroid's depth inside the sphere). The
// fraction moves with X at rate u / (2 sqrt(3) sigma): the gradient of the cut cells' share.
constexpr float kMaxFracSlope = 4.f;

UPD_VECTOR_CLONES
void sumAtNode(const Candidates& c, float X, float Y, float Z, float m, NodeSums& out) {
  float acc[16][kLanes] = {};
  const float m2 = m * m;
  const std::size_t n = c.size();
  using C = Candidates;
  const float* __restrict lx = c[C::kLx];
  const float* __restrict ly = c[C::kLy];
  const float* __restrict lz = c[C::kLz];
  const float* __restrict mx = c[C::kMx];
  const float* __restrict my = c[C::kMy];
  const float* __restrict mz = c[C::kMz];
  const float* __restrict cxx = c[C::kCxx];
  const float* __restrict cxy = c[C::kCxy];
  const float* __restrict cxz = c[C::kCxz];
  const float* __restrict cyy = c[C::kCyy];
  const float* __restrict cyz = c[C::kCyz];
  const float* __restrict czz = c[C::kCzz];
  const float* __restrict cnt = c[C::kCount];
  const float* __restrict nx = c[C::kNx];
  const float* __restrict ny = c[C::kNy];
  const float* __restrict nz = c[C::kNz];
  for (std::size_t j0 = 0; j0 < n; j0 += kLanes) {
    for (int l = 0; l < kLanes; ++l) {
      const std::size_t j = j0 + l;
      float near2, far2;
      boxDistances2(lx[j] - X, ly[j] - Y, lz[j] - Z, near2, far2);
      // The cut fraction from the centroid.
      const float vx = mx[j] - X, vy = my[j] - Y, vz = mz[j] - Z;
      const float d2 = vx * vx + vy * vy + vz * vz + 1e-12f;
      const float inv_d = detail::rsqrtNewton<2>(d2);
      const float dist = d2 * inv_d;
      const float q = vx * vx * cxx[j] + vy * vy * cyy[j] + vz * vz * czz[j] +
                      2.f * (vx * vy * cxy[j] + vx * vz * cxz[j] + vy * vz * cyz[j]);
      const float var = q * inv_d * inv_d;
      const float inv_w = 0.5f * detail::rsqrtNewton<2>(3.f * var + 1e-12f);
      const float soft = 0.5f + (m - dist) * inv_w;
      const float clamped = std::min(1.f, std::max(0.f, soft));
      const float wholly_in = far2 <= m2 ? 1.f : 0.f;
      const float touched = near2 > m2 ? 0.f : 1.f;
      const float frac = touched * std::max(wholly_in, clamped);
      const float cut =
          (soft > 0.f ? 1.f : 0.f) * (soft < 1.f ? 1.f : 0.f) * (1.f - wholly_in) * touched;
      // A cell whose points are spread thinly along u has a near-step fraction and a spike
      // for a gradient, so the slope is capped at kMaxFracSlope per cell (a ramp no steeper
      // than a quarter of a cell). A cap of 1 biased the node gradients where the ball's edge
      // meets a wall: equal labels on region_growing rose from 98.6 to 99.0 % with 4.
      const float g = cut * std::min(inv_w, kMaxFracSlope) * inv_d;
      const float gx = vx * g, gy = vy * g, gz = vz * g;
      acc[0][l] += frac * nx[j];
      acc[1][l] += frac * ny[j];
      acc[2][l] += frac * nz[j];
      acc[3][l] += frac * cnt[j];
      acc[4][l] += gx * nx[j];
      acc[5][l] += gx * ny[j];
      acc[6][l] += gx * nz[j];
      acc[7][l] += gx * cnt[j];
      acc[8][l] += gy * nx[j];
      acc[9][l] += gy * ny[j];
      acc[10][l] += gy * nz[j];
      acc[11][l] += gy * cnt[j];
      acc[12][l] += gz * nx[j];
      acc[13][l] += gz * ny[j];
      acc[14][l] += gz * nz[j];
      acc[15][l] += gz * cnt[j];
    }
  }
  for (int a = 0; a < 16; ++a) {
    float s = 0.f;
    for (int l = 0; l < kLanes; ++l) s += acc[a][l];
    out.q[a / 4][a % 4] = s;
  }
}

// Squared gap along each axis between the cell [l, l + 1] (l: its lower corner relative to the
// block's origin) and the lower [0, half - 1] or upper [half, B - 1] node range.
void octantGaps(const std::int32_t* xyz, const std::int32_t (&origin)[3], std::int32_t half,
                std::int32_t B, std::int32_t (&gap2)[3][2]) {
  for (int a = 0; a < 3; ++a) {
    const std::int32_t l = xyz[a] - origin[a];
    const std::int32_t lower = std::max({0, l - (half - 1), -(l + 1)});
    const std::int32_t upper = std::max({0, l - (B - 1), half - (l + 1)});
    gap2[a][0] = lower * lower, gap2[a][1] = upper * upper;
  }
}

// A thread's work space for the node sums of a block: the block's nodes by octant and the
// candidate cells of each octant.
struct OctantWork {
  std::array<Candidates, 8> cand;
  std::vector<std::uint32_t> cells;
  std::array<std::vector<std::uint32_t>, 8> octant;
};

// The ball sums at the nodes of block b. The nodes go in 8 groups, the block's octants (local
// coordinates below or from `half` along each axis); a group sums over the cells that some
// ball around its part of the block may touch (box distance <= m), a third to a half of the
// block's candidates.
void blockNodeSums(const LatticeIndex& index, const Bins& bins, const CellRow* rows, int m,
                   std::size_t b, OctantWork& w, NodeSums* node_sums) {
  const std::int32_t B = index.B, half = (B + 1) / 2;
  std::int32_t origin[3];
  index.blockOrigin(b, origin);
  for (auto& o : w.octant) o.clear();
  const CellLists& nodes = index.block_nodes;
  for (std::uint32_t q = nodes.start[b]; q < nodes.start[b + 1]; ++q) {
    const std::uint32_t v = nodes.order[q];
    int o = 0;
    for (int a = 0; a < 3; ++a) o |= (index.nodeXyz(v)[a] - origin[a] >= half ? 1 : 0) << a;
    w.octant[o].push_back(v);
  }
  index.around(b, bins.sums, w.cells);
  unsigned with_nodes = 0;  // bit o: octant o has nodes
  for (int o = 0; o < 8; ++o) {
    w.cand[o].reset(w.cells.size());
    with_nodes |= (w.octant[o].empty() ? 0u : 1u) << o;
  }
  const std::int32_t* cell_xyz = bins.grid.coords().data();
  float row[Candidates::kFields];
  for (const std::uint32_t c : w.cells) {
    std::int32_t gap2[3][2];
    octantGaps(&cell_xyz[3 * c], origin, half, B, gap2);
    // The octants some ball may reach the cell from, as a mask (no branch per octant); then
    // the cell's row once, appended to each of them in octant order.
    unsigned reach = 0;
    for (int o = 0; o < 8; ++o) {
      const std::int32_t d2 = gap2[0][o & 1] + gap2[1][(o >> 1) & 1] + gap2[2][o >> 2];
      reach |= (d2 <= m * m ? 1u : 0u) << o;
    }
    reach &= with_nodes;
    if (reach == 0) continue;
    Candidates::rowOf(c, cell_xyz, rows, origin, row);
    for (; reach != 0; reach &= reach - 1) w.cand[__builtin_ctz(reach)].append(row);
  }
  const auto mf = static_cast<float>(m);
  for (int o = 0; o < 8; ++o) {
    if (w.octant[o].empty()) continue;
    w.cand[o].pad();
    for (const std::uint32_t v : w.octant[o]) {
      const std::int32_t* xyz = index.nodeXyz(v);
      sumAtNode(w.cand[o], static_cast<float>(xyz[0] - origin[0]),
                static_cast<float>(xyz[1] - origin[1]), static_cast<float>(xyz[2] - origin[2]), mf,
                node_sums[v]);
    }
  }
}

// Scores the points members[from, to) (all of one cell, whose block is b) from the lattice
// sums at their own position; returns the points left unscored.
std::size_t scoreAtOwnPositions(const FastFrame& f, const LatticeIndex& index, const Bins& bins,
                                const CellRow* rows, std::size_t b, const std::uint32_t* members,
                                std::size_t from, std::size_t to, Candidates& cand,
                                std::vector<std::uint32_t>& cells, UpdResult& out) {
  std::int32_t origin[3];
  index.blockOrigin(b, origin);
  index.around(b, bins.sums, cells);
  cand.fill(cells.size(), cells.data(), bins.grid.coords().data(), rows, origin);
  const auto min_k = static_cast<float>(f.params.min_neighbors);
  const auto mf = static_cast<float>(f.m);
  const Lattice& lat = f.lat;
  std::size_t invalid = 0;
  NodeSums sum;
  for (std::size_t q = from; q < to; ++q) {
    const std::uint32_t i = members[q];
    sumAtNode(cand, lat.gx(f.cloud.x[i]) - static_cast<float>(origin[0]),
              lat.gy(f.cloud.y[i]) - static_cast<float>(origin[1]),
              lat.gz(f.cloud.z[i]) - static_cast<float>(origin[2]), mf, sum);
    const Quad& v = sum.q[0];
    if (!(v[3] + 0.5f >= min_k)) {
      setUnscored(out, i);
      ++invalid;
      continue;
    }
    out.rx[i] = v[0];
    out.ry[i] = v[1];
    out.rz[i] = v[2];
    out.zeta[i] = std::min(1.f, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / v[3]);
    out.k[i] = static_cast<std::uint32_t>(v[3] + 0.5f);
  }
  return invalid;
}

}  // namespace

void LatticeIndex::around(std::size_t b, const std::vector<CellSums>& sums,
                          std::vector<std::uint32_t>& cells) const {
  cells.clear();
  const std::int32_t* xyz = blocks.xyz(b);
  for (int d = 0; d < 27; ++d) {
    // (Blocks hold B > 1 cells a side: their coordinates and their neighbours' fit the key.)
    const std::uint32_t nb =
        blocks.findFitting(xyz[0] + d % 3 - 1, xyz[1] + (d / 3) % 3 - 1, xyz[2] + d / 9 - 1);
    if (nb == kNoIndex) continue;
    for (std::uint32_t q = block_cells.start[nb]; q < block_cells.start[nb + 1]; ++q) {
      if (sums[block_cells.order[q]].count > 0.f) cells.push_back(block_cells.order[q]);
    }
  }
}

namespace {

// The node at corner o of the cell at xyz, as an index of ranks.
inline std::size_t cornerIndex(const RankedCells& ranks, const std::int32_t* xyz, int o) {
  return ranks.index(cornerCoord(xyz, o, 0), cornerCoord(xyz, o, 1), cornerCoord(xyz, o, 2));
}

// The nodes of the cells [b, e) by rank into cell_nodes (8 a cell). (A function of its own,
// cloned: on x86-64-v3 and up GCC makes the rank's bit count one POPCNT.)
UPD_VECTOR_CLONES
void rankedCorners(const RankedCells& ranks, const std::int32_t* cell_xyz, std::size_t b,
                   std::size_t e, std::uint32_t* cell_nodes) {
  for (std::size_t c = b; c < e; ++c) {
    for (int o = 0; o < 8; ++o) cell_nodes[8 * c + o] = ranks.id(cornerIndex(ranks, &cell_xyz[3 * c], o));
  }
}

}  // namespace

// By rank in the bit table over the nodes' box: the same ids on any number of threads.
bool rankNodes(const std::int32_t* cell_xyz, std::size_t n_cells, LatticeIndex& index,
               std::uint32_t* cell_nodes) {
  index.ranked = false;
  if (n_cells == 0) return false;
  std::int32_t lo[3] = {cell_xyz[0], cell_xyz[1], cell_xyz[2]}, hi[3] = {lo[0], lo[1], lo[2]};
  for (std::size_t c = 1; c < n_cells; ++c) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], cell_xyz[3 * c + a]), hi[a] = std::max(hi[a], cell_xyz[3 * c + a]);
    }
  }
  for (std::int32_t& h : hi) ++h;  // (the upper corners of the last cells)
  RankedCells& ranks = index.node_ranks;
  if (!ranks.reset(lo, hi, 0, 8 * n_cells)) return false;
  constexpr std::size_t kTeamCells = 1024;
#pragma omp parallel if (n_cells > kTeamCells)
  {
    ranks.buildTeam(8 * n_cells, [&](std::size_t i) {
      return cornerIndex(ranks, &cell_xyz[3 * (i / 8)], static_cast<int>(i % 8));
    });
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    rankedCorners(ranks, cell_xyz, RankedCells::share(n_cells, team, me),
                  RankedCells::share(n_cells, team, me + 1), cell_nodes);
#pragma omp single
    index.ranked_node_xyz.resize(3 * ranks.size());
    ranks.cellsTeam(index.ranked_node_xyz.data());
  }
  index.ranked = true;
  return true;
}

// By the hash: ids in order of first sight.
void hashNodes(const std::int32_t* cell_xyz, std::size_t n_cells, LatticeIndex& index,
               std::uint32_t* cell_nodes) {
  index.ranked = false;
  index.nodes.clear(4 * n_cells);  // (its table and coordinates kept from the last frame)
  index.nodes.reserve(4 * n_cells);
  for (std::size_t c = 0; c < n_cells; ++c) {
    const std::int32_t* xyz = &cell_xyz[3 * c];
    for (int o = 0; o < 8; ++o) {
      cell_nodes[8 * c + o] = index.nodes.insert(cornerCoord(xyz, o, 0), cornerCoord(xyz, o, 1),
                                                 cornerCoord(xyz, o, 2));
    }
  }
}

void indexLattice(const Bins& bins, int m, LatticeIndex& index,
                  std::vector<std::uint32_t>& cell_nodes) {
  const std::size_t n_cells = bins.sums.size();
  const std::int32_t* cell_xyz = bins.grid.coords().data();
  cell_nodes.resize(8 * n_cells);
  if (!rankNodes(cell_xyz, n_cells, index, cell_nodes.data())) {
    hashNodes(cell_xyz, n_cells, index, cell_nodes.data());
  }
  // Blocks of B^3 cells; cells and nodes grouped by block (counting sort).
  const std::int32_t B = m + 1;
  index.B = B;
  index.blocks.clear(n_cells / 8 + 64);
  const FloorDivider byB(B);
  const auto blockOf = [&](const std::int32_t* xyz) {
    return index.blocks.insert(byB(xyz[0]), byB(xyz[1]), byB(xyz[2]));
  };
  const std::size_t n_nodes = index.nodeCount();
  index.cell_block.resize(n_cells), index.node_block.resize(n_nodes);
  for (std::size_t c = 0; c < n_cells; ++c) index.cell_block[c] = blockOf(&cell_xyz[3 * c]);
  for (std::size_t v = 0; v < n_nodes; ++v) index.node_block[v] = blockOf(index.nodeXyz(v));
  const std::size_t n_blocks = index.blocks.size();
  listByCell(
      n_cells, n_blocks, [&](std::size_t c) { return index.cell_block[c]; }, index.block_cells);
  listByCell(
      n_nodes, n_blocks, [&](std::size_t v) { return index.node_block[v]; }, index.block_nodes);
}

void computeCellRows(const std::vector<CellSums>& sums, std::vector<CellRow>& rows) {
  const std::size_t n_cells = sums.size();
  rows.resize(n_cells);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
    const CellSums& s = sums[static_cast<std::size_t>(cc)];
    const float inv = s.count > 0.f ? 1.f / s.count : 0.f;
    const float mx = s.px * inv, my = s.py * inv, mz = s.pz * inv;
    rows[static_cast<std::size_t>(cc)] = {
        {mx, my, mz, std::max(0.f, s.pxx * inv - mx * mx), s.pxy * inv - mx * my,
         s.pxz * inv - mx * mz, std::max(0.f, s.pyy * inv - my * my), s.pyz * inv - my * mz,
         std::max(0.f, s.pzz * inv - mz * mz), s.count, s.nx, s.ny, s.nz}};
  }
}

void computeNodeSums(const LatticeIndex& index, const Bins& bins, const CellRow* rows, int m,
                     std::vector<NodeSums>& node_sums) {
  node_sums.resize(index.nodeCount());
  NodeSums* const sums = node_sums.data();
  const std::size_t n_blocks = index.blocks.size();
#pragma omp parallel
  {
    OctantWork w;
#pragma omp for schedule(dynamic, 2)
    for (std::ptrdiff_t bb = 0; bb < static_cast<std::ptrdiff_t>(n_blocks); ++bb) {
      const auto b = static_cast<std::size_t>(bb);
      if (index.block_nodes.empty(b)) continue;
      blockNodeSums(index, bins, rows, m, b, w, sums);
    }
  }
}

// Cells where interpolation is not to be trusted: the zeta of their 8 nodes spreads by more
// than fast_refine_spread, i.e. the ball's edge meets a step, riser or wall within the cell
// and zeta bends sharply there. Their points get the lattice sums at their own position
// instead (the same cell sums, no interpolation): exact where the cut cells are thin, as a
// riser seen edge-on is.
std::vector<char> cellsToRefine(const NodeSums* node_sums, const std::uint32_t* cell_nodes,
                                std::size_t n_cells, double spread_limit) {
  std::vector<char> refine(n_cells, 0);
  if (!(spread_limit > 0)) return refine;
  const auto spread = static_cast<float>(spread_limit);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
    const auto c = static_cast<std::size_t>(cc);
    // Nodes with a small share of the cell's data (beyond the edge of the data, off the
    // surface) have an erratic zeta of their own: only the nodes with at least half the
    // largest k of the cell count.
    float k_max = 0.f;
    for (int o = 0; o < 8; ++o) k_max = std::max(k_max, node_sums[cell_nodes[8 * c + o]].q[0][3]);
    float lo = 2.f, hi = -1.f;
    for (int o = 0; o < 8; ++o) {
      const Quad& v = node_sums[cell_nodes[8 * c + o]].q[0];
      if (!(v[3] >= 0.5f * k_max) || !(v[3] >= 1.f)) continue;
      const float zeta = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]) / v[3];
      lo = std::min(lo, zeta), hi = std::max(hi, zeta);
    }
    refine[c] = hi - lo > spread ? 1 : 0;
  }
  return refine;
}

// The points of the refined cells, cell by cell, from the sums at their own position.
std::size_t scoreRefinedCells(const FastFrame& f, const LatticeIndex& index, const Bins& bins,
                              const CellRow* rows, const std::vector<char>& refine, UpdResult& out,
                              std::size_t& refined_points) {
  const std::size_t n_cells = bins.sums.size();
  const std::uint32_t* cell_of = f.cell_of;
  CellLists members;
  listByCell(
      f.cloud.size(), n_cells,
      [&](std::size_t i) {
        return cell_of[i] != kNoIndex && refine[cell_of[i]] ? cell_of[i] : kNoIndex;
      },
      members);
  refined_points = members.order.size();
  std::size_t invalid = 0;
#pragma omp parallel reduction(+ : invalid)
  {
    Candidates cand;
    std::vector<std::uint32_t> cells;
#pragma omp for schedule(dynamic, 4)
    for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
      const auto c = static_cast<std::size_t>(cc);
      if (members.empty(c)) continue;
      invalid +=
          scoreAtOwnPositions(f, index, bins, rows, index.cell_block[c], members.order.data(),
                              members.start[c], members.start[c + 1], cand, cells, out);
    }
  }
  return invalid;
}

}  // namespace upd::core::detail
