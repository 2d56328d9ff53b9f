// The fast UPD's interpolation stage: every point takes r and k from the blend of its cell's 8
// nodes (a cubic Hermite blend kept per cell as the coefficients of its polynomial), then zeta
// = |r| / k (eq. 8).
#include <algorithm>
#include <cmath>
#include <limits>

#include "fast_upd_internal.h"

namespace upd::core::detail {

namespace {

// Sixteen and eight floats as one GCC vector (AVX-512, or split into narrower vectors).
typedef float Vec16 __attribute__((vector_size(16 * sizeof(float))));
typedef float Vec8 __attribute__((vector_size(8 * sizeof(float))));

// Vec16 read in place from a plain array (no 64-byte alignment asked, any alias): the vector
// loads feed the multiply-adds directly. (Copied out by memcpy, the 8 vectors of a cell were
// moved through the stack 16 bytes at a time, half of a point's instructions.)
typedef float Vec16Unaligned __attribute__((vector_size(16 * sizeof(float)), aligned(4), may_alias));
inline const Vec16Unaligned& vec16At(const float* p) {
  return *reinterpret_cast<const Vec16Unaligned*>(p);
}

// The blend of a cell's 8 nodes as a polynomial. Each point of the cell takes r and k from
// its nodes: trilinear weights w_o, and each node's value carried towards the point by half
// its gradient step. For a quadratic field the trilinear blend errs by +E and the blend of
// first-order Taylor steps by -E, so their mean (this cubic Hermite blend) is exact.
// Rearranged, value(f) = A(f) + fx Bx(f) + fy By(f) + fz Bz(f) for f in [0, 1)^3, where A
// blends the node values less half their gradient step to the cell's lower corner and B_a
// blends half the gradients along a, each a trilinear form c0 + c1 fx + c2 fy + c3 fz +
// c4 fx fy + c5 fx fz + c6 fy fz + c7 fx fy fz. The 8 coefficients of the 4 forms of the 4
// values (r_x, r_y, r_z, k) are kept per cell as 8 vectors of 16 floats (CellBlend), so a point
// costs 8 vector multiply-adds instead of reading 8 nodes.
CellBlend cellBlend(const NodeSums* node_sums, const std::uint32_t* corner) {
  // X[form][o]: the corner values each form blends.
  Quad X[4][8];
  for (int o = 0; o < 8; ++o) {
    const NodeSums& s = node_sums[corner[o]];
    const float ox = static_cast<float>(o & 1), oy = static_cast<float>((o >> 1) & 1),
                oz = static_cast<float>(o >> 2);
    X[0][o] = s.q[0] - 0.5f * (s.q[1] * ox + s.q[2] * oy + s.q[3] * oz);
    for (int a = 0; a < 3; ++a) X[1 + a][o] = 0.5f * s.q[1 + a];
  }
  CellBlend b;
  for (int form = 0; form < 4; ++form) {
    const Quad* x = X[form];
    const Quad c[8] = {x[0],
                       x[1] - x[0],
                       x[2] - x[0],
                       x[4] - x[0],
                       x[3] - x[1] - x[2] + x[0],
                       x[5] - x[1] - x[4] + x[0],
                       x[6] - x[2] - x[4] + x[0],
                       x[7] - x[3] - x[5] - x[6] + x[1] + x[2] + x[4] - x[0]};
    for (int k = 0; k < 8; ++k) {
      for (int v = 0; v < 4; ++v) b.c[k][form * 4 + v] = c[k][v];
    }
  }
  return b;
}

// r, k and zeta of points [begin, end) from the blends of their cells; points without a cell
// or with k rounded below min_k get NaN. Points of cells marked in skip are left alone.
// Returns the points left unscored.
UPD_VECTOR_CLONES
std::size_t interpolate(const PointCloud& cloud, const Lattice& lat, const std::uint32_t* cell_of,
                        const std::int32_t* cell_xyz, const CellBlend* blends, const char* skip,
                        float min_k, std::size_t begin, std::size_t end, UpdResult& out) {
  const float* __restrict X = cloud.x.data();
  const float* __restrict Y = cloud.y.data();
  const float* __restrict Z = cloud.z.data();
  float* __restrict rx = out.rx.data();
  float* __restrict ry = out.ry.data();
  float* __restrict rz = out.rz.data();
  float* __restrict zeta = out.zeta.data();
  std::uint32_t* __restrict k_out = out.k.data();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t invalid = 0;
  for (std::size_t i = begin; i < end; ++i) {
    const std::uint32_t c = cell_of[i];
    if (c == kNoIndex) {
      rx[i] = ry[i] = rz[i] = zeta[i] = nan;
      k_out[i] = 0;
      ++invalid;
      continue;
    }
    if (skip[c]) continue;
    const float fx = lat.gx(X[i]) - static_cast<float>(cell_xyz[3 * c]);
    const float fy = lat.gy(Y[i]) - static_cast<float>(cell_xyz[3 * c + 1]);
    const float fz = lat.gz(Z[i]) - static_cast<float>(cell_xyz[3 * c + 2]);
    const float(*k)[16] = blends[c].c;
    // Summed as a tree: short dependency chains let consecutive points overlap.
    const Vec16Unaligned* c8 = &vec16At(k[0]);
    const Vec16 forms =
        ((c8[0] + c8[1] * fx) + (c8[2] * fy + c8[3] * fz)) +
        ((c8[4] * (fx * fy) + c8[5] * (fx * fz)) + (c8[6] * (fy * fz) + c8[7] * (fx * fy * fz)));
    // value = A + fx Bx + fy By + fz Bz: weigh the 4 quarters, then add them pairwise.
    const Vec16 t =
        forms * Vec16{1.f, 1.f, 1.f, 1.f, fx, fx, fx, fx, fy, fy, fy, fy, fz, fz, fz, fz};
    const Vec8 h = __builtin_shufflevector(t, t, 0, 1, 2, 3, 4, 5, 6, 7) +
                   __builtin_shufflevector(t, t, 8, 9, 10, 11, 12, 13, 14, 15);
    const Quad value =
        __builtin_shufflevector(h, h, 0, 1, 2, 3) + __builtin_shufflevector(h, h, 4, 5, 6, 7);
    const float vx = value[0], vy = value[1], vz = value[2], count = value[3];
    const bool scored = count + 0.5f >= min_k;  // k rounded to the nearest integer
    invalid += scored ? 0 : 1;
    rx[i] = scored ? vx : nan;
    ry[i] = scored ? vy : nan;
    rz[i] = scored ? vz : nan;
    zeta[i] = scored ? count : nan;  // k as a float until zetaFromCounts
    k_out[i] = scored ? static_cast<std::uint32_t>(count + 0.5f) : 0;
  }
  return invalid;
}

// zeta = |r| / k (eq. 8) of points [begin, end), whose zeta holds k (NaN stays NaN). A loop
// of its own, so that it vectorizes: in interpolate's, the square root and the division
// made every point wait for the last.
UPD_VECTOR_CLONES
void zetaFromCounts(const float* __restrict rx, const float* __restrict ry,
                    const float* __restrict rz, float* __restrict zeta, std::size_t begin,
                    std::size_t end) {
  for (std::size_t i = begin; i < end; ++i) {
    const float count = zeta[i];
    // |r| / k = |r|^2 / sqrt(|r|^2 k^2), floored away from 0 so that r = 0 gives 0.
    const float r2 = rx[i] * rx[i] + ry[i] * ry[i] + rz[i] * rz[i];
    const float z = r2 * detail::rsqrtNewton(std::max(r2 * count * count, 1e-30f));
    // |r| <= k holds at every node; the gradient steps may break it by a rounding margin.
    zeta[i] = z > 1.f ? 1.f : z;  // NaN stays NaN
  }
}

}  // namespace

std::size_t interpolateFrame(const FastFrame& f, const Bins& bins, FastUpdBuffers& buf,
                             const std::vector<char>& refine, UpdResult& out) {
  const std::size_t n_cells = bins.sums.size();
  const NodeSums* node_sums = buf.node_sums.data();
  const std::uint32_t* cell_nodes = buf.cell_nodes.data();
  std::vector<CellBlend>& blends = buf.blends;
  blends.resize(n_cells);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
    const auto c = static_cast<std::size_t>(cc);
    if (!refine[c]) blends[c] = cellBlend(node_sums, &cell_nodes[8 * c]);
  }
  std::size_t invalid = 0;
  const PointChunks& chunks = f.chunks;
  const auto min_k = static_cast<float>(f.params.min_neighbors);
#pragma omp parallel for schedule(static) reduction(+ : invalid)
  for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(chunks.count); ++c) {
    const std::size_t begin = chunks.begin(static_cast<std::size_t>(c));
    const std::size_t end = chunks.end(static_cast<std::size_t>(c));
    invalid += interpolate(f.cloud, f.lat, f.cell_of, bins.grid.coords().data(), blends.data(),
                           refine.data(), min_k, begin, end, out);
    // (The points of refined cells get stale values here; scoreRefinedCells writes them.)
    zetaFromCounts(out.rx.data(), out.ry.data(), out.rz.data(), out.zeta.data(), begin, end);
  }
  return invalid;
}

}  // namespace upd::core::detail
