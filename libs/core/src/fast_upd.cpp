#include "upd/core/fast_upd.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <cstring>
#include <string>

#include "fast_cell_map.h"
#include "fast_simd.h"

namespace upd {

namespace {

using detail::CellMap;
using detail::kLanes;
using detail::kNoIndex;

// Per-cell sums over the points with a valid normal. Positions are relative to the cell's
// lower corner in cell units (in [0, 1)), so float keeps them exact enough anywhere.
struct CellSums {
  float count = 0;
  float nx = 0, ny = 0, nz = 0;
  float px = 0, py = 0, pz = 0;
  float pxx = 0, pxy = 0, pxz = 0, pyy = 0, pyz = 0, pzz = 0;

  void add(const CellSums& o) {
    count += o.count;
    nx += o.nx, ny += o.ny, nz += o.nz;
    px += o.px, py += o.py, pz += o.pz;
    pxx += o.pxx, pxy += o.pxy, pxz += o.pxz, pyy += o.pyy, pyz += o.pyz, pzz += o.pzz;
  }
};

// Four floats as one GCC vector (SSE everywhere): r_x, r_y, r_z, k.
typedef float Quad __attribute__((vector_size(4 * sizeof(float))));
// Sixteen and eight floats likewise (AVX-512, or split into narrower vectors).
typedef float Vec16 __attribute__((vector_size(16 * sizeof(float))));
typedef float Vec8 __attribute__((vector_size(8 * sizeof(float))));

// Vec16 from a plain array (no 64-byte alignment asked). Through a reference: a function
// returning a 64-byte vector has a different ABI with and without AVX-512.
inline void loadVec16(Vec16& v, const float* p) { std::memcpy(&v, p, sizeof v); }

// Ball sums at a node: (r_x, r_y, r_z, k), then their derivatives with respect to the node's
// x, y and z (cell units), four values each: the layout the interpolation reads.
struct NodeSums {
  Quad q[4];
};

// What a cell contributes to ball sums, once per cell: the centroid's offset from the cell's
// lower corner and the covariance of its points (cell units), the count of valid normals and
// their sum.
struct CellRow {
  enum Field { kMx, kMy, kMz, kCxx, kCxy, kCxz, kCyy, kCyz, kCzz, kCount, kNx, kNy, kNz, kFields };
  float f[kFields];
};

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

// Squared nearest and farthest distance from a point to a unit cell whose lower corner lies at
// (ax, ay, az) from it. (Written as selects: GCC keeps the loops that call it branch-free and
// vectorizes them.)
inline void boxDistances2(float ax, float ay, float az, float& near2, float& far2) {
  const float bx = ax + 1.f, by = ay + 1.f, bz = az + 1.f;
  const float qx = ax > 0.f ? ax : (bx < 0.f ? -bx : 0.f);
  const float qy = ay > 0.f ? ay : (by < 0.f ? -by : 0.f);
  const float qz = az > 0.f ? az : (bz < 0.f ? -bz : 0.f);
  near2 = qx * qx + qy * qy + qz * qz;
  far2 = std::max(ax * ax, bx * bx) + std::max(ay * ay, by * by) + std::max(az * az, bz * bz);
}

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

struct Lattice {
  float rx = 0, ry = 0, rz = 0;  // world position of lattice point (0, 0, 0): the first point
  float inv_cell = 1.f;          // 1 / s

  // Lattice coordinates of a world point. The cloud's coordinates are floats: their difference
  // from the first point is exact wherever both lie on a common binary grid (a cloud moved by
  // 10 km gives the same numbers), so float keeps everything the input holds.
  float gx(float x) const { return (x - rx) * inv_cell; }
  float gy(float y) const { return (y - ry) * inv_cell; }
  float gz(float z) const { return (z - rz) * inv_cell; }
};

// Largest |lattice coordinate| the keys hold (21 bits per axis), with a margin for the nodes.
constexpr float kMaxCoord = static_cast<float>(detail::kKeyBias - 4);

// The occupied cells of a run of points: what binning produces per chunk and after merging.
struct Bins {
  CellMap map;
  std::vector<std::int32_t> xyz;  // 3 per cell
  std::vector<CellSums> sums;

  std::uint32_t cellOf(std::int32_t x, std::int32_t y, std::int32_t z) {
    bool inserted = false;
    const std::uint32_t id = map.findOrInsert(detail::packKey(x, y, z), inserted);
    if (inserted) {
      xyz.insert(xyz.end(), {x, y, z});
      sums.emplace_back();
    }
    return id;
  }
};

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

UPD_VECTOR_CLONES
void toLattice(const float* __restrict x, const float* __restrict y, const float* __restrict z,
               const float* __restrict nx, const float* __restrict ny, const float* __restrict nz,
               const Lattice& lat, std::size_t n, Stripe& __restrict s) {
  for (std::size_t j = 0; j < n; ++j) {
    const float gx = lat.gx(x[j]), gy = lat.gy(y[j]), gz = lat.gz(z[j]);
    // NaN and infinity fail this test too. (& rather than &&, floors as floats, everything
    // loaded and computed before it is selected: no branch, so the loop vectorizes.)
    const bool inside =
        (std::fabs(gx) < kMaxCoord) & (std::fabs(gy) < kMaxCoord) & (std::fabs(gz) < kMaxCoord);
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

inline void setUnscored(UpdResult& out, std::size_t i) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  out.rx[i] = out.ry[i] = out.rz[i] = out.zeta[i] = nan;
  out.k[i] = 0;
}

// The blend of a cell's 8 nodes as a polynomial. Each point of the cell takes r and k from
// its nodes: trilinear weights w_o, and each node's value carried towards the point by half
// its gradient step. For a quadratic field the trilinear blend errs by +E and the blend of
// first-order Taylor steps by -E, so their mean (this cubic Hermite blend) is exact.
// Rearranged, value(f) = A(f) + fx Bx(f) + fy By(f) + fz Bz(f) for f in [0, 1)^3, where A
// blends the node values less half their gradient step to the cell's lower corner and B_a
// blends half the gradients along a, each a trilinear form c0 + c1 fx + c2 fy + c3 fz +
// c4 fx fy + c5 fx fz + c6 fy fz + c7 fx fy fz. The 8 coefficients of the 4 forms of the 4
// values (r_x, r_y, r_z, k) are kept per cell as 8 vectors of 16 floats, so a point costs 8
// vector multiply-adds instead of reading 8 nodes.
struct CellBlend {
  float c[8][16];  // c[monomial][form * 4 + value], forms A, Bx, By, Bz (read as Vec16)
};

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
    Vec16 c8[8];
    for (int m = 0; m < 8; ++m) loadVec16(c8[m], k[m]);
    const Vec16 forms = ((c8[0] + c8[1] * fx) + (c8[2] * fy + c8[3] * fz)) +
                        ((c8[4] * (fx * fy) + c8[5] * (fx * fz)) +
                         (c8[6] * (fy * fz) + c8[7] * (fx * fy * fz)));
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

// --- Exact sums near the label threshold (UpdParams::fast_exact_band) ---

// The points with a valid normal grouped by cell (counting sort; point order within a cell),
// positions relative to the lattice origin (as in Lattice: the differences stay exact where
// the input floats allow it, so a cloud far from the origin loses nothing): what the exact
// sums over a cut cell read.
struct CellPoints {
  std::vector<std::uint32_t> start;  // n_cells + 1
  std::vector<float> x, y, z, nx, ny, nz;
};

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
        const float w = (dx * dx + dy * dy + dz * dz <= r2) & (l < valid) ? 1.f : 0.f;
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

// Bins points [first, cloud.size()) in chunks of chunk points (binRange), then merges the
// chunks' cells in chunk order; cell_of[i] is then point i's cell in the result.
Bins binPoints(const PointCloud& cloud, const Normals& normals, const Lattice& lat,
               std::size_t first, std::size_t chunk, double radius_m, std::uint32_t* cell_of) {
  const std::size_t n_pts = cloud.size();
  const std::size_t n_chunks = (n_pts - first + chunk - 1) / chunk;
  std::vector<Bins> chunk_bins(n_chunks);
  int all_fit = 1;
  // Static schedules here and in computeUpdFast's stages: every stage of a frame deals the
  // points out to the threads in the same contiguous shares, so that a point's data stay in one
  // core's cache (see copyCloud). Dynamic schedules scattered them, and on a two-vCPU VM a line
  // the other core has read costs twice as much to write again.
#pragma omp parallel for schedule(static) reduction(& : all_fit)
  for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(n_chunks); ++c) {
    const std::size_t begin = first + static_cast<std::size_t>(c) * chunk;
    all_fit &=
        binRange(cloud, normals, lat, begin, std::min(n_pts, begin + chunk), chunk_bins[c], cell_of)
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
  std::vector<std::vector<std::uint32_t>> remap(n_chunks);
  for (std::size_t c = 1; c < n_chunks; ++c) {
    const Bins& cb = chunk_bins[c];
    remap[c].resize(cb.sums.size());
    for (std::size_t j = 0; j < cb.sums.size(); ++j) {
      const std::uint32_t id = bins.cellOf(cb.xyz[3 * j], cb.xyz[3 * j + 1], cb.xyz[3 * j + 2]);
      bins.sums[id].add(cb.sums[j]);
      remap[c][j] = id;
    }
  }
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(n_chunks); ++c) {
    if (c == 0) continue;  // (from 0: the same shares as the binning)
    const std::size_t begin = first + static_cast<std::size_t>(c) * chunk;
    const std::size_t end = std::min(n_pts, begin + chunk);
    for (std::size_t i = begin; i < end; ++i) {
      if (cell_of[i] != kNoIndex) cell_of[i] = remap[c][cell_of[i]];
    }
  }
  return bins;
}

}  // namespace

int finerCellsPerRadius(int cells_per_radius, std::size_t cells, double valid_points,
                        double cells_per_point) {
  const int top = std::min(2 * cells_per_radius, 16);
  int m = cells_per_radius;
  // On a surface the occupied cells grow as the square of the cells per d_m.
  while (m < top) {
    const double ratio = static_cast<double>(m + 1) / cells_per_radius;
    if (static_cast<double>(cells) * ratio * ratio > cells_per_point * valid_points) break;
    ++m;
  }
  return m;
}

UpdResult computeUpdFast(const PointCloud& cloud, const Normals& normals, const UpdParams& params,
                         FastUpdStats* stats, double zeta_threshold) {
  UpdResult out;
  computeUpdFast(cloud, normals, params, out, stats, zeta_threshold);
  return out;
}

void computeUpdFast(const PointCloud& cloud, const Normals& normals, const UpdParams& params,
                    UpdResult& out, FastUpdStats* stats, double zeta_threshold) {
  params.validate();
  requireParam(params.knn == 0, "UpdParams", "knn", params.knn,
               "the fast path sums over the radius d_m: it needs knn = 0");
  const std::size_t n_pts = cloud.size();
  if (normals.size() != n_pts) {
    throw std::invalid_argument("computeUpdFast: " + std::to_string(normals.size()) +
                                " normals for " + std::to_string(n_pts) + " points");
  }
  // Every point's fields are written below (scored or NaN): no fill, and the caller's
  // buffers are reused from frame to frame.
  out.rx.resize(n_pts), out.ry.resize(n_pts), out.rz.resize(n_pts), out.zeta.resize(n_pts);
  out.k.resize(n_pts);
  out.invalid = 0;
  if (stats) *stats = FastUpdStats{};

  int m = params.fast_cells_per_radius;  // or finer, below
  Lattice lat;
  lat.inv_cell = static_cast<float>(m / params.radius_m);
  std::size_t first = 0;
  while (first < n_pts && !cloud.isFinite(first)) ++first;
  for (std::size_t i = 0; i < first; ++i) setUnscored(out, i);
  if (first == n_pts) {
    out.invalid = n_pts;
    return;
  }
  lat.rx = cloud.x[first], lat.ry = cloud.y[first], lat.rz = cloud.z[first];

  // 1. Bin the points, in fixed chunks (so the result does not depend on the thread count),
  // then merge the chunks' cells in chunk order.
  // The cell of every point (kNoIndex: none), in a buffer kept for the next frame; its
  // pointer is taken here, outside the parallel regions that share it.
  static thread_local std::vector<std::uint32_t> cell_of_buffer;
  cell_of_buffer.resize(n_pts);
  std::uint32_t* const cell_of = cell_of_buffer.data();
  std::fill(cell_of, cell_of + first, kNoIndex);
  // Chunks of equal size, at most 2^15 points (a multiple of 256), from the number of points
  // alone: the same for any number of threads, and a static schedule gives two threads an
  // equal share.
  const std::size_t n_chunks = (n_pts - first + (std::size_t(1) << 15) - 1) >> 15;
  const std::size_t kChunk = ((n_pts - first + n_chunks - 1) / n_chunks + 255) / 256 * 256;
  Bins bins = binPoints(cloud, normals, lat, first, kChunk, params.radius_m, cell_of);
  // A finer lattice where the points are dense (fast_cells_per_point): the node work grows
  // with the cells, so it stays a fixed share of the per-point work.
  if (params.fast_cells_per_point > 0) {
    double valid = 0;
    for (const CellSums& cs : bins.sums) valid += cs.count;
    const int finer = finerCellsPerRadius(m, bins.sums.size(), valid, params.fast_cells_per_point);
    if (finer > m) {
      m = finer;
      lat.inv_cell = static_cast<float>(m / params.radius_m);
      bins = binPoints(cloud, normals, lat, first, kChunk, params.radius_m, cell_of);
    }
  }
  const std::vector<std::int32_t>& cell_xyz = bins.xyz;
  const std::vector<CellSums>& sums = bins.sums;
  const std::size_t n_cells = sums.size();

  // 2. Lattice nodes: the 8 corners of every occupied cell.
  // The per-cell and per-node tables below live in the calling thread's buffers, kept for the
  // next frame (as cell_of): a frame loop does not fault fresh pages in for them every frame.
  // Every element read is written first. (Referenced through locals: inside a parallel region
  // the name of a thread_local would be another thread's buffer.)
  static thread_local std::vector<std::uint32_t> cell_nodes_buffer;
  std::vector<std::uint32_t>& cell_nodes = cell_nodes_buffer;
  cell_nodes.resize(8 * n_cells);
  std::vector<std::int32_t> node_xyz;
  {
    CellMap node_map(4 * n_cells);
    node_xyz.reserve(3 * 4 * n_cells);
    for (std::size_t c = 0; c < n_cells; ++c) {
      for (int o = 0; o < 8; ++o) {
        const std::int32_t x = cell_xyz[3 * c] + (o & 1), y = cell_xyz[3 * c + 1] + ((o >> 1) & 1),
                           z = cell_xyz[3 * c + 2] + ((o >> 2) & 1);
        bool inserted = false;
        const std::uint32_t id = node_map.findOrInsert(detail::packKey(x, y, z), inserted);
        if (inserted) node_xyz.insert(node_xyz.end(), {x, y, z});
        cell_nodes[8 * c + o] = id;
      }
    }
  }
  const std::size_t n_nodes = node_xyz.size() / 3;

  // 3. Blocks of B^3 cells with B = m + 1: every cell within d_m of a node lies in the 27
  // blocks around the node's block. Cells and nodes are grouped by block (counting sort).
  const std::int32_t B = m + 1;
  CellMap block_map(n_cells / 8 + 64);
  std::vector<std::int32_t> block_xyz;
  const auto blockOf = [&](std::int32_t x, std::int32_t y, std::int32_t z) {
    const std::int32_t bx = detail::floorDiv(x, B), by = detail::floorDiv(y, B),
                       bz = detail::floorDiv(z, B);
    bool inserted = false;
    const std::uint32_t id = block_map.findOrInsert(detail::packKey(bx, by, bz), inserted);
    if (inserted) block_xyz.insert(block_xyz.end(), {bx, by, bz});
    return id;
  };
  std::vector<std::uint32_t> cell_block(n_cells), node_block(n_nodes);
  for (std::size_t c = 0; c < n_cells; ++c) {
    cell_block[c] = blockOf(cell_xyz[3 * c], cell_xyz[3 * c + 1], cell_xyz[3 * c + 2]);
  }
  for (std::size_t v = 0; v < n_nodes; ++v) {
    node_block[v] = blockOf(node_xyz[3 * v], node_xyz[3 * v + 1], node_xyz[3 * v + 2]);
  }
  const std::size_t n_blocks = block_xyz.size() / 3;
  const auto groupBy = [n_blocks](const std::vector<std::uint32_t>& owner,
                                  std::vector<std::uint32_t>& start,
                                  std::vector<std::uint32_t>& order) {
    start.assign(n_blocks + 1, 0);
    for (const std::uint32_t b : owner) ++start[b + 1];
    for (std::size_t b = 0; b < n_blocks; ++b) start[b + 1] += start[b];
    order.resize(owner.size());
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < owner.size(); ++i) {
      order[fill[owner[i]]++] = static_cast<std::uint32_t>(i);
    }
  };
  std::vector<std::uint32_t> cell_start, cell_order, node_start, node_order;
  groupBy(cell_block, cell_start, cell_order);
  groupBy(node_block, node_start, node_order);

  // What every cell with valid normals contributes, once; and for every block the cells of
  // the 27 blocks around it (every cell within d_m of one of its nodes).
  static thread_local std::vector<CellRow> rows_buffer;
  std::vector<CellRow>& rows = rows_buffer;
  rows.resize(n_cells);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
    const CellSums& s = sums[static_cast<std::size_t>(cc)];
    const float inv = s.count > 0.f ? 1.f / s.count : 0.f;
    const float mx = s.px * inv, my = s.py * inv, mz = s.pz * inv;
    rows[static_cast<std::size_t>(cc)] = {{mx, my, mz, std::max(0.f, s.pxx * inv - mx * mx),
                                           s.pxy * inv - mx * my, s.pxz * inv - mx * mz,
                                           std::max(0.f, s.pyy * inv - my * my),
                                           s.pyz * inv - my * mz,
                                           std::max(0.f, s.pzz * inv - mz * mz), s.count, s.nx,
                                           s.ny, s.nz}};
  }
  const auto around = [&](std::size_t b, std::vector<std::uint32_t>& cells) {
    cells.clear();
    for (int d = 0; d < 27; ++d) {
      const std::uint32_t nb = block_map.find(
          detail::packKey(block_xyz[3 * b] + d % 3 - 1, block_xyz[3 * b + 1] + (d / 3) % 3 - 1,
                          block_xyz[3 * b + 2] + d / 9 - 1));
      if (nb == kNoIndex) continue;
      for (std::uint32_t q = cell_start[nb]; q < cell_start[nb + 1]; ++q) {
        if (sums[cell_order[q]].count > 0.f) cells.push_back(cell_order[q]);
      }
    }
  };
  const auto blockOrigin = [&](std::size_t b, std::int32_t origin[3]) {
    for (int a = 0; a < 3; ++a) origin[a] = block_xyz[3 * b + a] * B;
  };

  // 4. Ball sums at every node. The nodes of a block go in 8 groups, its octants (local
  // coordinates below or from `half` along each axis); a group sums over the cells that some
  // ball around its part of the block may touch (box distance <= m), a third to a half of the
  // block's candidates.
  static thread_local std::vector<NodeSums> node_sums_buffer;
  std::vector<NodeSums>& node_sums = node_sums_buffer;
  node_sums.resize(n_nodes);
  const float mf = static_cast<float>(m);
  const std::int32_t half = (B + 1) / 2;
#pragma omp parallel
  {
    std::array<Candidates, 8> cand;  // per octant
    std::vector<std::uint32_t> cells;
    std::array<std::vector<std::uint32_t>, 8> octant;
#pragma omp for schedule(dynamic, 2)
    for (std::ptrdiff_t bb = 0; bb < static_cast<std::ptrdiff_t>(n_blocks); ++bb) {
      const auto b = static_cast<std::size_t>(bb);
      if (node_start[b] == node_start[b + 1]) continue;
      std::int32_t origin[3];
      blockOrigin(b, origin);
      for (auto& o : octant) o.clear();
      for (std::uint32_t q = node_start[b]; q < node_start[b + 1]; ++q) {
        const std::uint32_t v = node_order[q];
        int o = 0;
        for (int a = 0; a < 3; ++a) o |= (node_xyz[3 * v + a] - origin[a] >= half ? 1 : 0) << a;
        octant[o].push_back(v);
      }
      around(b, cells);
      for (int o = 0; o < 8; ++o) cand[o].reset(cells.size());
      float row[Candidates::kFields];
      for (const std::uint32_t c : cells) {
        // Squared gap along each axis between the cell [l, l + 1] and the lower [0, half - 1]
        // or upper [half, B - 1] node range.
        std::int32_t gap2[3][2];
        for (int a = 0; a < 3; ++a) {
          const std::int32_t l = cell_xyz[3 * c + a] - origin[a];
          const std::int32_t lower = std::max({0, l - (half - 1), -(l + 1)});
          const std::int32_t upper = std::max({0, l - (B - 1), half - (l + 1)});
          gap2[a][0] = lower * lower, gap2[a][1] = upper * upper;
        }
        Candidates::rowOf(c, cell_xyz.data(), rows.data(), origin, row);
        for (int o = 0; o < 8; ++o) {
          const std::int32_t d2 = gap2[0][o & 1] + gap2[1][(o >> 1) & 1] + gap2[2][o >> 2];
          if (d2 <= m * m && !octant[o].empty()) cand[o].append(row);
        }
      }
      for (int o = 0; o < 8; ++o) {
        if (octant[o].empty()) continue;
        cand[o].pad();
        for (const std::uint32_t v : octant[o]) {
          sumAtNode(cand[o], static_cast<float>(node_xyz[3 * v] - origin[0]),
                    static_cast<float>(node_xyz[3 * v + 1] - origin[1]),
                    static_cast<float>(node_xyz[3 * v + 2] - origin[2]), mf, node_sums[v]);
        }
      }
    }
  }

  // Cells where interpolation is not to be trusted: the zeta of their 8 nodes spreads by more
  // than fast_refine_spread, i.e. the ball's edge meets a step, riser or wall within the cell
  // and zeta bends sharply there. Their points get the lattice sums at their own position
  // instead (the same cell sums, no interpolation): exact where the cut cells are thin, as a
  // riser seen edge-on is.
  std::vector<char> refine(n_cells, 0);
  std::size_t refined_points = 0;
  if (params.fast_refine_spread > 0) {
    const auto spread = static_cast<float>(params.fast_refine_spread);
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
  }

  // 5. Every point from the blend of its cell's 8 nodes (interpolate, above), in chunks.
  static thread_local std::vector<CellBlend> blends_buffer;
  std::vector<CellBlend>& blends = blends_buffer;
  blends.resize(n_cells);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
    const auto c = static_cast<std::size_t>(cc);
    if (!refine[c]) blends[c] = cellBlend(node_sums.data(), &cell_nodes[8 * c]);
  }
  std::size_t invalid = first;  // the points before the first finite one
  const std::size_t n_blocks_pts = (n_pts - first + kChunk - 1) / kChunk;
#pragma omp parallel for schedule(static) reduction(+ : invalid)
  for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(n_blocks_pts); ++c) {
    const std::size_t begin = first + static_cast<std::size_t>(c) * kChunk;
    const std::size_t end = std::min(n_pts, begin + kChunk);
    invalid += interpolate(cloud, lat, cell_of, cell_xyz.data(), blends.data(), refine.data(),
                           static_cast<float>(params.min_neighbors), begin, end, out);
    // (The points of refined cells get stale values here; step 6 writes them.)
    zetaFromCounts(out.rx.data(), out.ry.data(), out.rz.data(), out.zeta.data(), begin, end);
  }
  // 6. The points of the refined cells, cell by cell, from the sums at their own position.
  if (params.fast_refine_spread > 0) {
    std::vector<std::uint32_t> start(n_cells + 1, 0);
    for (std::size_t i = 0; i < n_pts; ++i) {
      if (cell_of[i] != kNoIndex && refine[cell_of[i]]) ++start[cell_of[i] + 1];
    }
    for (std::size_t c = 0; c < n_cells; ++c) start[c + 1] += start[c];
    std::vector<std::uint32_t> members(start[n_cells]);
    {
      std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
      for (std::size_t i = 0; i < n_pts; ++i) {
        if (cell_of[i] != kNoIndex && refine[cell_of[i]]) {
          members[fill[cell_of[i]]++] = static_cast<std::uint32_t>(i);
        }
      }
    }
    refined_points = members.size();
    const auto min_k = static_cast<float>(params.min_neighbors);
#pragma omp parallel reduction(+ : invalid)
    {
      Candidates cand;
      std::vector<std::uint32_t> cells;
      NodeSums sum;
#pragma omp for schedule(dynamic, 4)
      for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
        const auto c = static_cast<std::size_t>(cc);
        if (start[c] == start[c + 1]) continue;
        const std::size_t b = cell_block[c];
        std::int32_t origin[3];
        blockOrigin(b, origin);
        around(b, cells);
        cand.fill(cells.size(), cells.data(), cell_xyz.data(), rows.data(), origin);
        for (std::uint32_t q = start[c]; q < start[c + 1]; ++q) {
          const std::uint32_t i = members[q];
          sumAtNode(cand, lat.gx(cloud.x[i]) - static_cast<float>(origin[0]),
                    lat.gy(cloud.y[i]) - static_cast<float>(origin[1]),
                    lat.gz(cloud.z[i]) - static_cast<float>(origin[2]), mf, sum);
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
      }
    }
  }
  // 7. Exact sums for the points whose zeta lies within fast_exact_band of the label threshold:
  // their label is then the exact path's. A cell wholly inside the ball adds its sums, one
  // wholly outside nothing, and the points of a cell the sphere cuts are tested one by one.
  std::size_t exact_points = 0;
  if (params.fast_exact_band > 0 && std::isfinite(zeta_threshold)) {
    const auto lo = static_cast<float>(zeta_threshold - params.fast_exact_band);
    const auto hi = static_cast<float>(zeta_threshold + params.fast_exact_band);
    // The points to sum exactly (per chunk, in point order) and the valid-normal points per
    // chunk and cell (for the counting sort below), in the binning's shares.
    std::vector<std::vector<std::uint32_t>> chosen(n_blocks_pts);
    std::vector<std::uint32_t> chunk_count(n_blocks_pts * n_cells, 0);
#pragma omp parallel for schedule(static)
    for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(n_blocks_pts); ++c) {
      const std::size_t begin = first + static_cast<std::size_t>(c) * kChunk;
      const std::size_t end = std::min(n_pts, begin + kChunk);
      std::uint32_t* count = &chunk_count[static_cast<std::size_t>(c) * n_cells];
      for (std::size_t i = begin; i < end; ++i) {
        const std::uint32_t cell = cell_of[i];
        if (cell == kNoIndex) continue;
        if (out.zeta[i] > lo && out.zeta[i] < hi) {
          chosen[c].push_back(static_cast<std::uint32_t>(i));
        }
        if (normals.isValid(i)) ++count[cell];
      }
    }
    for (const auto& v : chosen) exact_points += v.size();
    if (exact_points > 0) {
      // Counting sort of the valid-normal points by cell, chunk by chunk: the same order for
      // any number of threads.
      static thread_local CellPoints points_buffer;
      CellPoints& pts = points_buffer;
      pts.start.assign(n_cells + 1, 0);
      for (std::size_t cell = 0; cell < n_cells; ++cell) {
        std::uint32_t at = pts.start[cell];
        for (std::size_t c = 0; c < n_blocks_pts; ++c) {
          const std::uint32_t k = chunk_count[c * n_cells + cell];
          chunk_count[c * n_cells + cell] = at;  // now the chunk's first slot in the cell
          at += k;
        }
        pts.start[cell + 1] = at;
      }
      const std::size_t n_valid = pts.start[n_cells];
      // (kLanes more: sumPointsWithin reads whole vectors, masking the lanes past a range.)
      for (auto* v : {&pts.x, &pts.y, &pts.z, &pts.nx, &pts.ny, &pts.nz}) {
        v->assign(n_valid + kLanes, 0.f);
      }
#pragma omp parallel for schedule(static)
      for (std::ptrdiff_t c = 0; c < static_cast<std::ptrdiff_t>(n_blocks_pts); ++c) {
        const std::size_t begin = first + static_cast<std::size_t>(c) * kChunk;
        const std::size_t end = std::min(n_pts, begin + kChunk);
        std::uint32_t* slot = &chunk_count[static_cast<std::size_t>(c) * n_cells];
        for (std::size_t i = begin; i < end; ++i) {
          const std::uint32_t cell = cell_of[i];
          if (cell == kNoIndex || !normals.isValid(i)) continue;
          const std::uint32_t j = slot[cell]++;
          pts.x[j] = cloud.x[i] - lat.rx, pts.y[j] = cloud.y[i] - lat.ry;
          pts.z[j] = cloud.z[i] - lat.rz;
          pts.nx[j] = normals.nx[i], pts.ny[j] = normals.ny[i], pts.nz[j] = normals.nz[i];
        }
      }
      // The chosen points grouped by cell: each cell's candidates are gathered once.
      std::vector<std::uint32_t> chosen_start(n_cells + 1, 0), chosen_order(exact_points);
      for (const auto& v : chosen) {
        for (const std::uint32_t i : v) ++chosen_start[cell_of[i] + 1];
      }
      for (std::size_t cell = 0; cell < n_cells; ++cell) {
        chosen_start[cell + 1] += chosen_start[cell];
      }
      {
        std::vector<std::uint32_t> fill(chosen_start.begin(), chosen_start.end() - 1);
        for (const auto& v : chosen) {
          for (const std::uint32_t i : v) chosen_order[fill[cell_of[i]]++] = i;
        }
      }
      const float m2 = mf * mf;
      const float in2 = m2 * (1.f - 1e-4f), out2 = m2 * (1.f + 1e-4f);
      const auto radius = static_cast<float>(params.radius_m);
      const float r2 = radius * radius;
      const auto min_k = static_cast<std::uint32_t>(params.min_neighbors);
      std::size_t newly_invalid = 0;
#pragma omp parallel reduction(+ : newly_invalid)
      {
        ExactCandidates cand;
        std::vector<std::uint32_t> cells;
        ExactScratch scratch;
#pragma omp for schedule(dynamic, 2)
        for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
          const auto c = static_cast<std::size_t>(cc);
          if (chosen_start[c] == chosen_start[c + 1]) continue;
          around(cell_block[c], cells);
          cand.gather(cells, c, m, cell_xyz.data(), sums.data());
          const std::int32_t* own = &cell_xyz[3 * c];
          for (std::uint32_t q = chosen_start[c]; q < chosen_start[c + 1]; ++q) {
            const std::uint32_t i = chosen_order[q];
            const float q_cell[3] = {lat.gx(cloud.x[i]) - static_cast<float>(own[0]),
                                     lat.gy(cloud.y[i]) - static_cast<float>(own[1]),
                                     lat.gz(cloud.z[i]) - static_cast<float>(own[2])};
            const float q_world[3] = {cloud.x[i] - lat.rx, cloud.y[i] - lat.ry,
                                      cloud.z[i] - lat.rz};
            float acc[4];
            exactBallSums(cand, pts, q_cell, q_world, in2, out2, r2, scratch, acc);
            const auto k = static_cast<std::uint32_t>(acc[3] + 0.5f);
            if (k < min_k) {
              setUnscored(out, i);
              ++newly_invalid;
              continue;
            }
            out.rx[i] = acc[0], out.ry[i] = acc[1], out.rz[i] = acc[2];
            const double r_norm = std::sqrt(double(acc[0]) * acc[0] + double(acc[1]) * acc[1] +
                                            double(acc[2]) * acc[2]);
            out.zeta[i] = static_cast<float>(r_norm / k);
            out.k[i] = k;
          }
        }
      }
      invalid += newly_invalid;
    }
  }
  out.invalid = invalid;
  if (stats) {
    stats->exact_points = exact_points;
    stats->cells = n_cells;
    stats->nodes = n_nodes;
    stats->blocks = n_blocks;
    stats->refined_points = refined_points;
    stats->cells_per_radius = m;
  }
}

}  // namespace upd
