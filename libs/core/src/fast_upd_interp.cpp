// The fast UPD's interpolation stage: every point takes r and k from the blend of its cell's 8
// nodes (a cubic Hermite blend kept per cell as the coefficients of its polynomial), then zeta
// = |r| / k (eq. 8).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "fast_upd_internal.h"

namespace upd::core::detail {

namespace {

// The blend of a cell's 8 nodes as a polynomial. Each point of the cell takes r and k from
// its nodes: trilinear weights w_o, and each node's value carried towards the point by half
// its gradient step. For a quadratic field the trilinear blend errs by +E and the blend of
// first-order Taylor steps by -E, so their mean (this cubic Hermite blend) is exact.
// Rearranged, value(f) = A(f) + fx Bx(f) + fy By(f) + fz Bz(f) for f in [0, 1)^3, where A
// blends the node values less half their gradient step to the cell's lower corner and B_a
// blends half the gradients along a, each a trilinear form c0 + c1 fx + c2 fy + c3 fz +
// c4 fx fy + c5 fx fz + c6 fy fz + c7 fx fy fz. Multiplied out, the value is a polynomial of
// 20 monomials (kMonomials), whose coefficients are kept per cell (CellPoly): the points
// of a run in one cell are then evaluated a vector of points at a time, 80 multiply-adds per
// vector of 8.
CellPoly cellPoly(const NodeSums* node_sums, const std::uint32_t* corner,
                  const std::int32_t* cell_xyz) {
  // X[form][o]: the corner values each form blends.
  Quad X[4][8];
  for (int o = 0; o < 8; ++o) {
    const NodeSums& s = node_sums[corner[o]];
    const float ox = static_cast<float>(o & 1), oy = static_cast<float>((o >> 1) & 1),
                oz = static_cast<float>(o >> 2);
    X[0][o] = s.q[0] - 0.5f * (s.q[1] * ox + s.q[2] * oy + s.q[3] * oz);
    for (int a = 0; a < 3; ++a) X[1 + a][o] = 0.5f * s.q[1 + a];
  }
  // F[form][k]: the trilinear coefficients (1, fx, fy, fz, fx fy, fx fz, fy fz, fx fy fz).
  Quad F[4][8];
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
    for (int k = 0; k < 8; ++k) F[form][k] = c[k];
  }
  const Quad* A = F[0];
  const Quad* Bx = F[1];
  const Quad* By = F[2];
  const Quad* Bz = F[3];
  // In the order of the monomials evaluate() forms.
  const Quad m[kMonomials] = {A[0],                            // 1
                              A[1] + Bx[0],                    // fx
                              A[2] + By[0],                    // fy
                              A[3] + Bz[0],                    // fz
                              A[4] + Bx[2] + By[1],            // fx fy
                              A[5] + Bx[3] + Bz[1],            // fx fz
                              A[6] + By[3] + Bz[2],            // fy fz
                              A[7] + Bx[6] + By[5] + Bz[4],    // fx fy fz
                              Bx[1],                           // fx^2
                              By[2],                           // fy^2
                              Bz[3],                           // fz^2
                              Bx[4],                           // fx^2 fy
                              Bx[5],                           // fx^2 fz
                              By[4],                           // fx fy^2
                              By[6],                           // fy^2 fz
                              Bz[5],                           // fx fz^2
                              Bz[6],                           // fy fz^2
                              Bx[7],                           // fx^2 fy fz
                              By[7],                           // fx fy^2 fz
                              Bz[7]};                          // fx fy fz^2
  CellPoly p;
  for (int k = 0; k < kMonomials; ++k) p.c[k] = m[k];
  for (int a = 0; a < 3; ++a) p.corner[a] = static_cast<float>(cell_xyz[a]);
  return p;
}

constexpr int kRunLanes = 8;
typedef float Lanes __attribute__((vector_size(kRunLanes * sizeof(float))));
typedef std::int32_t LaneMask __attribute__((vector_size(kRunLanes * sizeof(std::int32_t))));

// The four values at kRunLanes points of one cell (x, y, z: their coordinates) from the cell's
// polynomial.
__attribute__((always_inline)) inline void evaluate(const CellPoly& p, const Lattice& lat,
                                                    const Lanes& x, const Lanes& y, const Lanes& z,
                                                    Lanes (&value)[4]) {
  const Lanes fx = (x - lat.rx) * lat.inv_cell - p.corner[0];
  const Lanes fy = (y - lat.ry) * lat.inv_cell - p.corner[1];
  const Lanes fz = (z - lat.rz) * lat.inv_cell - p.corner[2];
  const Lanes xy = fx * fy, xz = fx * fz, yz = fy * fz, xx = fx * fx, yy = fy * fy, zz = fz * fz;
  const Lanes mono[kMonomials] = {Lanes{} + 1.f, fx,      fy,      fz,      xy,      xz,
                                  yz,            xy * fz, xx,      yy,      zz,      xx * fy,
                                  xx * fz,       fx * yy, yy * fz, fx * zz, fy * zz, xx * yz,
                                  yy * xz,       zz * xy};
  for (int v = 0; v < 4; ++v) {
    // Two chains, so that consecutive multiply-adds need not wait for each other.
    Lanes s0 = p.c[0][v] * mono[0], s1 = p.c[1][v] * mono[1];
    for (int k = 2; k < kMonomials; k += 2) {
      s0 += p.c[k][v] * mono[k];
      s1 += p.c[k + 1][v] * mono[k + 1];
    }
    value[v] = s0 + s1;
  }
}

// The four values at one point of the cell: the monomials' coefficients as vectors of the 4.
__attribute__((always_inline)) inline Quad evaluateOne(const CellPoly& p, const Lattice& lat,
                                                       float x, float y, float z) {
  const float fx = lat.gx(x) - p.corner[0], fy = lat.gy(y) - p.corner[1],
              fz = lat.gz(z) - p.corner[2];
  const float xy = fx * fy, xz = fx * fz, yz = fy * fz, xx = fx * fx, yy = fy * fy, zz = fz * fz;
  const Quad* c = p.c;
  // Summed as a tree: short dependency chains let consecutive points overlap.
  return ((c[0] + c[1] * fx + c[2] * fy + c[3] * fz) +
          (c[4] * xy + c[5] * xz + c[6] * yz + c[7] * (xy * fz))) +
         ((c[8] * xx + c[9] * yy + c[10] * zz + c[11] * (xx * fy)) +
          (c[12] * (xx * fz) + c[13] * (fx * yy) + c[14] * (yy * fz) + c[15] * (fx * zz)) +
          (c[16] * (fy * zz) + c[17] * (xx * yz) + c[18] * (yy * xz) + c[19] * (zz * xy)));
}

// Where interpolate writes a point's r, k and (until zetaFromCounts) k as a float.
struct PointOut {
  float* __restrict rx;
  float* __restrict ry;
  float* __restrict rz;
  float* __restrict zeta;
  std::uint32_t* __restrict k;
  float min_k;

  // Point j's values, or NaN where k rounds below min_k; returns 1 then, else 0.
  std::size_t store(std::size_t j, float vx, float vy, float vz, float count) const {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const bool scored = count + 0.5f >= min_k;  // k rounded to the nearest integer
    rx[j] = scored ? vx : nan;
    ry[j] = scored ? vy : nan;
    rz[j] = scored ? vz : nan;
    zeta[j] = scored ? count : nan;
    k[j] = scored ? static_cast<std::uint32_t>(count + 0.5f) : 0;
    return scored ? 0 : 1;
  }
  // Points [b, e) unscored (no cell: not finite, or beyond the lattice); returns e - b.
  std::size_t unscore(std::size_t b, std::size_t e) const {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (float* v : {rx, ry, rz, zeta}) std::fill(v + b, v + e, nan);
    std::fill(k + b, k + e, 0u);
    return e - b;
  }
  // The same as store for the kRunLanes points from j0.
  __attribute__((always_inline)) std::size_t storeLanes(std::size_t j0,
                                                        const Lanes (&value)[4]) const {
    const LaneMask scored = value[3] + 0.5f >= min_k;
    const Lanes nans = Lanes{} + std::numeric_limits<float>::quiet_NaN();
    const Lanes outs[4] = {scored ? value[0] : nans, scored ? value[1] : nans,
                           scored ? value[2] : nans, scored ? value[3] : nans};
    std::memcpy(rx + j0, &outs[0], sizeof(Lanes)), std::memcpy(ry + j0, &outs[1], sizeof(Lanes));
    std::memcpy(rz + j0, &outs[2], sizeof(Lanes)), std::memcpy(zeta + j0, &outs[3], sizeof(Lanes));
    const LaneMask k_lanes = __builtin_convertvector(value[3] + 0.5f, LaneMask) & scored;
    std::memcpy(k + j0, &k_lanes, sizeof k_lanes);
    std::size_t unscored = 0;
    for (int l = 0; l < kRunLanes; ++l) unscored += scored[l] ? 0 : 1;
    return unscored;
  }
};

// The points [i, e) of one cell: runs of at least kMinLanes points a vector of points at a time
// (a vector's 80 multiply-adds serve any number of its lanes), the rest one point at a time.
// Returns the points left unscored.
__attribute__((always_inline)) inline std::size_t scoreRun(const CellPoly& p, const Lattice& lat,
                                                           const float* X, const float* Y,
                                                           const float* Z, std::size_t i,
                                                           std::size_t e, const PointOut& out) {
  constexpr std::size_t kMinLanes = 5;
  std::size_t invalid = 0, j0 = i;
  for (; j0 + kMinLanes <= e; j0 += kRunLanes) {
    const std::size_t n = std::min<std::size_t>(kRunLanes, e - j0);
    // A short vector reads its points into lanes of its own (the rest repeat the first).
    Lanes x, y, z;
    if (n == kRunLanes) {
      std::memcpy(&x, X + j0, sizeof x), std::memcpy(&y, Y + j0, sizeof y);
      std::memcpy(&z, Z + j0, sizeof z);
    } else {
      for (int l = 0; l < kRunLanes; ++l) {
        const std::size_t j = j0 + (static_cast<std::size_t>(l) < n ? static_cast<std::size_t>(l) : 0);
        x[l] = X[j], y[l] = Y[j], z[l] = Z[j];
      }
    }
    Lanes value[4];
    evaluate(p, lat, x, y, z, value);
    if (n == kRunLanes) {
      invalid += out.storeLanes(j0, value);
      continue;
    }
    for (std::size_t l = 0; l < n; ++l) {
      invalid += out.store(j0 + l, value[0][l], value[1][l], value[2][l], value[3][l]);
    }
  }
  for (std::size_t j = j0; j < e; ++j) {
    const Quad v = evaluateOne(p, lat, X[j], Y[j], Z[j]);
    invalid += out.store(j, v[0], v[1], v[2], v[3]);
  }
  return invalid;
}

// r, k and zeta of points [begin, end) from the polynomials of their cells, a run of points
// in one cell at a time (scoreRun); points without a cell or with k rounded below min_k get
// NaN. Points of cells marked in skip are left alone. Returns the points left unscored.
UPD_VECTOR_CLONES
std::size_t interpolate(const PointCloud& cloud, const Lattice& lat, const std::uint32_t* cell_of,
                        const CellPoly* polys, const char* skip, float min_k, std::size_t begin,
                        std::size_t end, UpdResult& result) {
  const PointOut out{result.rx.data(),   result.ry.data(), result.rz.data(),
                     result.zeta.data(), result.k.data(),  min_k};
  std::size_t invalid = 0;
  for (std::size_t i = begin; i < end;) {
    const std::uint32_t c = cell_of[i];
    std::size_t e = i + 1;
    while (e < end && cell_of[e] == c) ++e;
    if (c == kNoIndex) {
      invalid += out.unscore(i, e);
    } else if (!skip[c]) {
      invalid += scoreRun(polys[c], lat, cloud.x.data(), cloud.y.data(), cloud.z.data(), i, e, out);
    }
    i = e;
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
  const std::int32_t* cell_xyz = bins.grid.coords().data();
  std::vector<CellPoly>& polys = buf.polys;
  polys.resize(n_cells);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
    const auto c = static_cast<std::size_t>(cc);
    if (!refine[c]) polys[c] = cellPoly(node_sums, &cell_nodes[8 * c], &cell_xyz[3 * c]);
  }
  std::size_t invalid = 0;
  const PointChunks& chunks = f.chunks;
  const auto min_k = static_cast<float>(f.params.min_neighbors);
#pragma omp parallel for schedule(dynamic, 1) reduction(+ : invalid)
  for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(chunks.count); ++c) {
    const std::size_t begin = chunks.begin(static_cast<std::size_t>(c));
    const std::size_t end = chunks.end(static_cast<std::size_t>(c));
    invalid += interpolate(f.cloud, f.lat, f.cell_of, polys.data(), refine.data(), min_k, begin,
                           end, out);
    // (The points of refined cells get stale values here; scoreRefinedCells writes them.)
    zetaFromCounts(out.rx.data(), out.ry.data(), out.rz.data(), out.zeta.data(), begin, end);
  }
  return invalid;
}

}  // namespace upd::core::detail
