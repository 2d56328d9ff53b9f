// The fast normals' arithmetic (the PCA normal from the moments of a neighbourhood) and the
// hash-grid path for unorganized clouds, computeNormalsGrid. The organized path is in
// fast_normals_organized.cpp; the vector loop both use, gatedMoments, in fast_normals_internal.h.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "chunk_deal.h"
#include "fast_cell_map.h"
#include "fast_cell_ranks.h"
#include "fast_normals_internal.h"
#include "upd/core/fast_normals.h"
#include "upd/core/vector_clones.h"

namespace upd::core::detail {

// The covariance of the moments, scaled to unit trace (a, b, c / d, e / f: its upper triangle),
// or false when it has no spread.
bool unitCovariance(const Moments& m, double (&cov)[6]) {
  if (!(m.n > 0)) return false;
  const double inv = 1.0 / m.n;
  const double mx = m.x * inv, my = m.y * inv, mz = m.z * inv;
  const double a = m.xx * inv - mx * mx, b = m.xy * inv - mx * my, c = m.xz * inv - mx * mz;
  const double d = m.yy * inv - my * my, e = m.yz * inv - my * mz, f = m.zz * inv - mz * mz;
  const double trace = a + d + f;
  if (!(trace > 0)) return false;
  const double s = 1.0 / trace;
  cov[0] = a * s, cov[1] = b * s, cov[2] = c * s, cov[3] = d * s, cov[4] = e * s, cov[5] = f * s;
  return true;
}

// The unoriented PCA normal of a covariance C scaled to unit trace (eqs. 4-5) and its
// curvature, or false for a neighbourhood without a plane (lambda_1 ~ 0, as pcaNormal).
//
// The eigenvector of the smallest eigenvalue of C is the dominant one of adj(C), whose
// eigenvalues are l1 l2 >= l0 l2 >= l0 l1 for l0 <= l1 <= l2, and so of B = adj(C)^2. The
// largest column of B is within (l0 / l1)^2 of it, and each product with B shrinks the error by
// (l0 / l1)^2 again: after three, (l0 / l1)^8, below 0.3 degrees even where l0 = l1 / 2 (a
// rounded edge) and at float precision on a surface; it goes on until it settles, and where
// l0 is close to l1 (no clear plane) the general eigen solver takes over. With unit trace the
// products neither overflow nor underflow.
bool normalFromUnitCovariance(const double (&cov)[6], Eigen::Vector3f& n, float& curvature) {
  const double a = cov[0], b = cov[1], c = cov[2], d = cov[3], e = cov[4], f = cov[5];
  const double A00 = d * f - e * e, A01 = c * e - b * f, A02 = b * e - c * d;
  const double A11 = a * f - c * c, A12 = b * c - a * e, A22 = a * d - b * b;
  // |adj| ~ l1 l2 / trace^2: a neighbourhood without a plane has l1 ~ 0 (pcaNormal's test).
  const double adj_norm2 =
      A00 * A00 + A11 * A11 + A22 * A22 + 2 * (A01 * A01 + A02 * A02 + A12 * A12);
  if (!(adj_norm2 > 1e-20)) return false;
  const double B00 = A00 * A00 + A01 * A01 + A02 * A02;
  const double B01 = A00 * A01 + A01 * A11 + A02 * A12;
  const double B02 = A00 * A02 + A01 * A12 + A02 * A22;
  const double B11 = A01 * A01 + A11 * A11 + A12 * A12;
  const double B12 = A01 * A02 + A11 * A12 + A12 * A22;
  const double B22 = A02 * A02 + A12 * A12 + A22 * A22;
  double vx, vy, vz;
  if (B00 >= B11 && B00 >= B22) {
    vx = B00, vy = B01, vz = B02;
  } else if (B11 >= B22) {
    vx = B01, vy = B11, vz = B12;
  } else {
    vx = B02, vy = B12, vz = B22;
  }
  for (int it = 0; it < 3; ++it) {
    const double wx = B00 * vx + B01 * vy + B02 * vz;
    const double wy = B01 * vx + B11 * vy + B12 * vz;
    const double wz = B02 * vx + B12 * vy + B22 * vz;
    vx = wx, vy = wy, vz = wz;
  }
  double norm2 = vx * vx + vy * vy + vz * vz;
  if (!(norm2 > 0) || !std::isfinite(norm2)) return false;
  double k = 1.0 / std::sqrt(norm2);
  vx *= k, vy *= k, vz *= k;
  // How close are l0 and l1? l0 is v's Rayleigh quotient; l1 and l2 then follow from the trace
  // (1 here) and the determinant. Where l1 < 2 l0 the iteration is slow to settle and the
  // neighbourhood hardly has a plane: the general eigen solver decides, as in pcaNormal.
  const double q0 = vx * (a * vx + b * vy + c * vz) + vy * (b * vx + d * vy + e * vz) +
                    vz * (c * vx + e * vy + f * vz);
  const double det = a * A00 + b * A01 + c * A02;
  const double rest = 1.0 - q0;
  const double l1 =
      q0 > 1e-12 ? 0.5 * (rest - std::sqrt(std::max(0.0, rest * rest - 4.0 * det / q0))) : rest;
  if (l1 < 2.0 * q0) {
    Eigen::Matrix3d C;
    C << a, b, c, b, d, e, c, e, f;
    // The closed-form 3 x 3 solver: in double, and with unit trace, its error (~1e-9 rad
    // over the gap of the eigenvalues) is far below what separates l0 from l1 here.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(C);
    if (es.info() != Eigen::Success) return false;
    const Eigen::Vector3d ev = es.eigenvalues();  // ascending, trace 1
    if (ev[1] <= 1e-10) return false;
    n = es.eigenvectors().col(0).cast<float>().normalized();
    curvature = static_cast<float>(std::max(0.0, ev[0]));
    return true;
  }
  // Otherwise each step shrinks the error by (l0 / l1)^2 < 1/4: go on until a step moves v by
  // less than 1e-5 rad.
  for (int it = 0; it < 20; ++it) {
    const double wx = B00 * vx + B01 * vy + B02 * vz;
    const double wy = B01 * vx + B11 * vy + B12 * vz;
    const double wz = B02 * vx + B12 * vy + B22 * vz;
    norm2 = wx * wx + wy * wy + wz * wz;
    if (!(norm2 > 0)) break;
    k = 1.0 / std::sqrt(norm2);
    const double cos_step = (wx * vx + wy * vy + wz * vz) * k;
    vx = wx * k, vy = wy * k, vz = wz * k;
    if (cos_step > 1.0 - 5e-11) break;
  }
  const double l0 =
      std::max(0.0, vx * (a * vx + b * vy + c * vz) + vy * (b * vx + d * vy + e * vz) +
                        vz * (c * vx + e * vy + f * vz));
  n = Eigen::Vector3f(static_cast<float>(vx), static_cast<float>(vy), static_cast<float>(vz));
  curvature = static_cast<float>(l0);  // lambda_0 / trace: C has unit trace here
  return true;
}

// The same from the moments of a neighbourhood (m.n is the sum of the weights). The caller
// checks that there are at least 3 points.
bool normalFromMoments(const Moments& m, Eigen::Vector3f& n, float& curvature) {
  double cov[6];
  return unitCovariance(m, cov) && normalFromUnitCovariance(cov, n, curvature);
}

}  // namespace upd::core::detail

namespace upd::core {

namespace {

using detail::kFar;
using detail::kNoIndex;
using detail::kScanLanes;
using detail::Moments;

// The finite points binned into cells of edge radius_m (the neighbours of a point lie in the 27
// cells around its own), grouped by cell and kept relative to the first finite point, as
// coordinate arrays. The cells are numbered by rank in their box widened by one cell and found
// by its table of one bit per cell (a load and a population count per neighbour cell, at an
// offset fixed per grid); where the table declines the box (far lone points), numbered in order
// of first sight and found by the hash grid.
struct RadiusGrid {
  detail::CellGrid grid;       // ids by hash, where the rank table is off
  std::vector<std::int32_t> xyz;  // 3 per cell, in id order
  std::size_t n_cells = 0;
  bool has_dense = false;
  detail::RankedCells dense;  // the cells by rank over the box widened by one cell
  detail::TeamCellCounts team_counts;  // (listByCellTeam's)
  std::array<std::int64_t, 9> dense_rows{};  // the rows of 3 cells around one: dy + 3 dz, at dx -1
  detail::CellLists points;    // cloud indices by cell
  std::uint32_t max_cell_points = 0;  // the most points in a cell
  std::vector<float> x, y, z;  // by cell: relative to the first finite point (then kFar slack)

  std::size_t denseIndex(const std::int32_t* c) const { return dense.index(c[0], c[1], c[2]); }
};

// The rank table over the box [lo, hi] widened by one cell (nothing marked) and the offsets of
// the 9 rows of 3 cells around a cell, or false where the table declines the box.
bool makeDense(RadiusGrid& g, const std::int32_t (&lo)[3], const std::int32_t (&hi)[3],
               std::size_t n_points) {
  if (!g.dense.reset(lo, hi, 1, n_points)) return false;
  for (int r = 0; r < 9; ++r) {
    g.dense_rows[static_cast<std::size_t>(r)] = g.dense.offset(-1, r % 3 - 1, r / 3 - 1);
  }
  return true;
}

// The most points in a cell and the grid's point rows sized (slack for gatherAround's copies,
// 8 at a time; the candidate rows have kScanLanes = 8 more), once the points are listed by cell.
// (Only the slack is filled here: copyByCell writes the rest on the team, each thread its share,
// and the rows keep their size from call to call.)
void sizeRows(RadiusGrid& g) {
  g.max_cell_points = g.points.mostInACell();
  const std::size_t n = g.points.order.size();
  g.x.resize(n + 8), g.y.resize(n + 8), g.z.resize(n + 8);
  detail::fillEight(kFar, g.x.data() + n, g.y.data() + n, g.z.data() + n);
}

// Grid points [s0, s1) (cloud points of the cells in id order) copied, relative to ref.
void copyByCell(const PointCloud& cloud, const Eigen::Vector3d& ref, RadiusGrid& g,
                std::size_t s0, std::size_t s1) {
  for (std::size_t s = s0; s < s1; ++s) {
    const Eigen::Vector3f q =
        (cloud.point(g.points.order[s]).cast<double>() - ref).cast<float>();
    g.x[s] = q.x(), g.y[s] = q.y(), g.z[s] = q.z();
  }
}

// Where the cells are numbered by rank: the cells of the finite points (cell_of not kNoIndex;
// their cells' coordinates in rows) marked, the points listed by cell and copied, on the team
// from 16,384 points (the same grid on any number of threads).
void rankAndCopy(const PointCloud& cloud, std::size_t first, const Eigen::Vector3d& ref,
                 const detail::CellRows& rows, std::uint32_t* cell_of, RadiusGrid& g) {
  const std::size_t N = cloud.size();
#pragma omp parallel if (N - first > 16384)
  detail::rankListAndCopyTeam(
      g.dense, rows, N, cell_of, g.points, g.team_counts, g.xyz,
      [&](std::size_t n_cells) { g.n_cells = n_cells, sizeRows(g); },
      [&](std::size_t s0, std::size_t s1) { copyByCell(cloud, ref, g, s0, s1); });
}

// The cells of edge 1 / inv of points [0, n) relative to ref: floor((double(x) - ref) * inv)
// along each axis into cx, cy and cz, clamped to +-2^30 (NaN to -2^30), which fails keyFits as
// any cell beyond the keys' range does. (Cloned: a vector of doubles at a time.)
UPD_VECTOR_CLONES
void cellsOfPoints(const float* __restrict x, const float* __restrict y,
                   const float* __restrict z, std::size_t n, double rx, double ry, double rz,
                   double inv, std::int32_t* __restrict cx, std::int32_t* __restrict cy,
                   std::int32_t* __restrict cz) {
  constexpr double kLimit = 1073741824.0;
  const auto cell = [&](float v, double r) {
    double c = std::floor((static_cast<double>(v) - r) * inv);
    c = c > -kLimit ? c : -kLimit;
    return static_cast<std::int32_t>(c < kLimit ? c : kLimit);
  };
  for (std::size_t i = 0; i < n; ++i) {
    cx[i] = cell(x[i], rx), cy[i] = cell(y[i], ry), cz[i] = cell(z[i], rz);
  }
}

// The grid g of the finite points of cloud (from first, the first of them) in cells of edge
// radius_m; the other points' normals in out set unset.
void binByRadius(const PointCloud& cloud, std::size_t first, double radius_m, RadiusGrid& g,
                 Normals& out) {
  const std::size_t N = cloud.size();
  const Eigen::Vector3d ref = cloud.point(first).cast<double>();
  const double inv = 1.0 / radius_m;
  // Every point's cell (by axis; a non-finite point's is not read) and the finite points' box.
  // (Not initialized: each thread writes its share, which stays in its core's cache.)
  const std::unique_ptr<std::int32_t[]> cells(new std::int32_t[3 * N]);
  std::int32_t *cx = cells.get(), *cy = cx + N, *cz = cy + N;
  const std::unique_ptr<std::uint32_t[]> cell_of_points(new std::uint32_t[N]);
  std::uint32_t* cell_of = cell_of_points.get();
  std::int32_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::numeric_limits<std::int32_t>::max();
    hi[a] = std::numeric_limits<std::int32_t>::min();
  }
  std::size_t n_finite = 0;
  bool fits = true;
  // (In static shares on the team: each point's cell by itself, the box by min and max.)
#pragma omp parallel if (N > 16384) reduction(min : lo[:3]) reduction(max : hi[:3]) \
    reduction(+ : n_finite) reduction(&& : fits)
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t b = detail::RankedCells::share(N, team, me);
    const std::size_t e = detail::RankedCells::share(N, team, me + 1);
    cellsOfPoints(&cloud.x[b], &cloud.y[b], &cloud.z[b], e - b, ref.x(), ref.y(), ref.z(), inv,
                  cx + b, cy + b, cz + b);
    for (std::size_t i = b; i < e; ++i) {
      cell_of[i] = kNoIndex;
      if (!cloud.isFinite(i)) {
        detail::setUnset(out, i);
        continue;
      }
      if (!detail::keyFits(cx[i], cy[i], cz[i])) {
        fits = false;
        continue;
      }
      const std::int32_t c[3] = {cx[i], cy[i], cz[i]};
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], c[a]), hi[a] = std::max(hi[a], c[a]);
      cell_of[i] = 0;  // (finite: numbered below)
      ++n_finite;
    }
  }
  if (!fits) {
    throw std::invalid_argument("NormalParams.radius_m = " + std::to_string(radius_m) +
                                ": the cloud spans more than 2^20 radii along an axis");
  }
  g.has_dense = makeDense(g, lo, hi, n_finite);
  if (g.has_dense) {
    rankAndCopy(cloud, first, ref, detail::CellRows{cx, cy, cz, 1}, cell_of, g);
    return;
  }
  g.grid = detail::CellGrid(N / 8 + 64);
  for (std::size_t i = first; i < N; ++i) {
    if (cell_of[i] == kNoIndex) continue;
    cell_of[i] = g.grid.insert(cx[i], cy[i], cz[i]);
  }
  g.xyz = g.grid.coords(), g.n_cells = g.grid.size();
  detail::listByCell(
      N, g.n_cells, [&](std::size_t i) { return cell_of[i]; }, g.points);
  sizeRows(g);
  const std::size_t n = g.points.order.size();
#pragma omp parallel if (n > 16384)
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    copyByCell(cloud, ref, g, detail::RankedCells::share(n, team, me),
               detail::RankedCells::share(n, team, me + 1));
  }
}

// cellsAround by the rank table, around the cell at index at: by rows of 3 along x, one
// population count a row. (Cloned: on x86-64-v3 and up GCC makes countBits one POPCNT.)
UPD_VECTOR_CLONES
int rankedAround(const RadiusGrid& g, std::size_t at, std::array<std::uint32_t, 27>& around) {
  int n_around = 0;
  for (const std::int64_t row : g.dense_rows) {
    std::uint32_t ids[3];
    g.dense.threeIds(at + static_cast<std::size_t>(row), ids);
    for (const std::uint32_t id : ids) {
      if (id != kNoIndex) around[static_cast<std::size_t>(n_around++)] = id;
    }
  }
  return n_around;
}

// The ids of the occupied cells among the 27 around cell c, in the order d = dx + 3 dy + 9 dz.
int cellsAround(const RadiusGrid& g, std::size_t c, std::array<std::uint32_t, 27>& around) {
  int n_around = 0;
  const std::int32_t* xyz = &g.xyz[3 * c];
  if (g.has_dense) return rankedAround(g, g.denseIndex(xyz), around);
  // (Away from the keys' bounds, as nearly always, the neighbours' keys are the cell's plus
  // an offset, with no range test.)
  static const std::array<std::uint64_t, 27> offsets = [] {
    std::array<std::uint64_t, 27> t{};
    for (int d = 0; d < 27; ++d) t[d] = detail::keyOffset(d % 3 - 1, (d / 3) % 3 - 1, d / 9 - 1);
    return t;
  }();
  const bool inner = detail::keyFitsAround(xyz, 1);
  const std::uint64_t key = inner ? detail::packKey(xyz[0], xyz[1], xyz[2]) : 0;
  for (int d = 0; d < 27; ++d) {
    const std::uint32_t id =
        inner ? g.grid.findKey(key + offsets[static_cast<std::size_t>(d)])
              : g.grid.find(xyz[0] + d % 3 - 1, xyz[1] + (d / 3) % 3 - 1, xyz[2] + d / 9 - 1);
    if (id != kNoIndex) around[static_cast<std::size_t>(n_around++)] = id;
  }
  return n_around;
}

// The candidates of the points of cell c (the points of the 27 cells around it), as coordinate
// rows for gatedMoments, padded with kFar; returns their number. The rows are resized to room
// for the fullest cell's points in each cell around (no count before the copy), never shrunk
// (no allocation once they have the room).
__attribute__((always_inline)) inline std::ptrdiff_t gatherAround(const RadiusGrid& g,
                                                                  std::size_t c,
                                                                  std::vector<float>& cx,
                                                                  std::vector<float>& cy,
                                                                  std::vector<float>& cz) {
  // (Not value-initialized: only the first n_around are read, each written first.)
  std::array<std::uint32_t, 27> around;
  const int n_around = cellsAround(g, c, around);
  const std::uint32_t* start = g.points.start.data();
  // (8: the copies' overrun past the last run.)
  const std::size_t room =
      std::min(g.points.order.size(), std::size_t{g.max_cell_points} * 27) + 8 + kScanLanes;
  if (cx.size() < room) cx.resize(room), cy.resize(room), cz.resize(room);
  float *ox = cx.data(), *oy = cy.data(), *oz = cz.data();
  std::size_t m = 0;
  for (int a = 0; a < n_around; ++a) {
    const std::uint32_t b = start[around[a]], e = start[around[a] + 1];
    detail::copyRunByEights(g.x.data(), g.y.data(), g.z.data(), b, e, ox + m, oy + m, oz + m);
    m += e - b;
  }
  static_assert(kScanLanes == 8, "the padding is one fillEight");
  detail::fillEight(kFar, ox + m, oy + m, oz + m);
  return static_cast<std::ptrdiff_t>(m);
}

// Moments relative to p of the candidates [0, n) within sqrt(radius2), weighted by a Gaussian
// of the distance (exp(-d^2 inv_2s2)); count is the number of them.
Moments gaussianMoments(const std::vector<float>& cx, const std::vector<float>& cy,
                        const std::vector<float>& cz, std::ptrdiff_t n, const Eigen::Vector3f& p,
                        float radius2, float inv_2s2, std::size_t& count) {
  Moments m;
  for (std::ptrdiff_t t = 0; t < n; ++t) {
    const Eigen::Vector3f q = Eigen::Vector3f(cx[t], cy[t], cz[t]) - p;
    const float d2 = q.squaredNorm();
    if (d2 > radius2) continue;
    const double w = std::exp(-d2 * inv_2s2);
    const double x = q.x(), y = q.y(), z = q.z();
    m.n += w, m.x += w * x, m.y += w * y, m.z += w * z;
    m.xx += w * x * x, m.xy += w * x * y, m.xz += w * x * z;
    m.yy += w * y * y, m.yz += w * y * z, m.zz += w * z * z;
    ++count;
  }
  return m;
}

// The moments of a thread's points' neighbourhoods, solved a batch at a time
// (detail::normalsFromMoments) and written, oriented, to their cloud indices.
class NormalBatch {
 public:
  // Adds the neighbourhood of point i (one without spread fails at the flush).
  void add(const Moments& m, std::size_t i) {
    const double f[10] = {m.n, m.x, m.y, m.z, m.xx, m.xy, m.xz, m.yy, m.yz, m.zz};
    for (std::size_t k = 0; k < 10; ++k) moments_[k][size_] = f[k];
    index_[size_++] = i;
  }
  bool full() const { return size_ == kSize; }
  // Solves and writes the batch; returns the number of points without a normal.
  template <class Orient>
  std::size_t flush(const PointCloud& cloud, const Orient& orient, Normals& out) {
    detail::normalsFromMoments(&moments_[0][0], kSize, size_, n_, curvature_, ok_);
    std::size_t failed = 0;
    for (std::size_t b = 0; b < size_; ++b) {
      const std::size_t i = index_[b];
      if (!ok_[b]) {
        detail::setUnset(out, i);
        ++failed;
        continue;
      }
      detail::setNormal(out, i, orient(n_[b], cloud.point(i)), curvature_[b]);
    }
    size_ = 0;
    return failed;
  }

 private:
  static constexpr std::size_t kSize = 64;
  std::size_t size_ = 0;
  double moments_[10][kSize];  // (by field, in Moments' order)
  std::size_t index_[kSize];
  Eigen::Vector3f n_[kSize];
  float curvature_[kSize];
  std::uint8_t ok_[kSize];
};

// The normals of the points of cell c: their candidates gathered, the moments of each point's
// ball added to the batch (weighted by a Gaussian of the distance where kGaussian), the batch
// flushed into out whenever it fills. Returns the number of points without a normal.
template <bool kGaussian>
__attribute__((always_inline)) inline std::size_t cellNormalsWith(
    const RadiusGrid& g, std::size_t c, float radius2, float inv_2s2, std::vector<float>& cx,
    std::vector<float>& cy, std::vector<float>& cz, NormalBatch& batch, const PointCloud& cloud,
    const NormalOrienter& orient, Normals& out) {
  const std::ptrdiff_t n_candidates = gatherAround(g, c, cx, cy, cz);
  // (The rows' length for gatedMoments: the candidates and one vector of padding.)
  const auto n_rows = static_cast<std::size_t>(n_candidates) + kScanLanes;
  std::size_t invalid = 0;
  for (std::uint32_t s = g.points.start[c]; s < g.points.start[c + 1]; ++s) {
    // Moments of the neighbours relative to p (eq. 4).
    const Eigen::Vector3f p(g.x[s], g.y[s], g.z[s]);
    std::size_t count = 0;
    const Moments m =
        kGaussian ? gaussianMoments(cx, cy, cz, n_candidates, p, radius2, inv_2s2, count)
                  : detail::gatedMomentsBody(cx.data(), cy.data(), cz.data(), n_rows, 0, 0, 0,
                                             n_candidates - 1, 1, p.x(), p.y(), p.z(), radius2);
    if (!kGaussian) count = static_cast<std::size_t>(m.n);
    if (count < 3) {
      detail::setUnset(out, g.points.order[s]);
      ++invalid;
      continue;
    }
    batch.add(m, g.points.order[s]);
    if (batch.full()) invalid += batch.flush(cloud, orient, out);
  }
  return invalid;
}

// The unweighted ones, cloned: the copies, the scans and the batch's stores at the machine's
// vector width, the scan inlined rather than called through its dispatcher.
UPD_VECTOR_CLONES
std::size_t cellNormals(const RadiusGrid& g, std::size_t c, float radius2,
                        std::vector<float>& cx, std::vector<float>& cy, std::vector<float>& cz,
                        NormalBatch& batch, const PointCloud& cloud,
                        const NormalOrienter& orient, Normals& out) {
  return cellNormalsWith<false>(g, c, radius2, 0.f, cx, cy, cz, batch, cloud, orient, out);
}

}  // namespace

Normals computeNormalsGrid(const PointCloud& cloud, const NormalParams& params,
                           const Eigen::Vector3f& up) {
  Normals out;
  computeNormalsGrid(cloud, params, up, out);
  return out;
}

void computeNormalsGrid(const PointCloud& cloud, const NormalParams& params,
                        const Eigen::Vector3f& up, Normals& out) {
  params.validate();
  requireParam(params.knn == 0, "NormalParams", "knn", params.knn,
               "computeNormalsGrid finds radius neighbourhoods: it needs knn = 0");
  const std::size_t N = cloud.size();
  std::size_t first = 0;
  while (first < N && !cloud.isFinite(first)) ++first;
  if (first == N) {
    out.setUnset(N);
    return;
  }
  // Every point's normal is written below, on the team (a normal, or NaN): the buffers are not
  // filled first, as a fill on one thread would leave the other threads' points in its core's
  // cache. The grid keeps its buffers from call to call (the calling thread's).
  out.nx.resize(N), out.ny.resize(N), out.nz.resize(N), out.curvature.resize(N);
  thread_local RadiusGrid kept;
  RadiusGrid& g = kept;
  binByRadius(cloud, first, params.radius_m, g, out);
  const float radius2 = static_cast<float>(params.radius_m * params.radius_m);
  const bool gaussian = params.weighting == NormalWeighting::Gaussian;
  const float sigma = 0.5f * static_cast<float>(params.radius_m);
  const float inv_2s2 = 1.f / (2.f * sigma * sigma);
  std::size_t invalid = N - g.points.order.size();
  const NormalOrienter orient(cloud.sensor_origin, up, params.vertical_band_rad);
  // (Chunks of 16 cells dealt by ChunkDeal: a cell's points are spread over the cloud, and the
  // normals are written by point.)
  detail::ChunkDeal deal(g.n_cells, 16, openmp::maxThreads());
#pragma omp parallel reduction(+ : invalid)
  {
    std::vector<float> cx, cy, cz;
    NormalBatch batch;
    detail::ChunkDeal::Hand hand(deal, openmp::threadIndex());
    for (std::size_t b, e; hand.next(b, e);) {
      for (std::size_t c = b; c < e; ++c) {
        invalid += gaussian ? cellNormalsWith<true>(g, c, radius2, inv_2s2, cx, cy, cz, batch,
                                                    cloud, orient, out)
                            : cellNormals(g, c, radius2, cx, cy, cz, batch, cloud, orient, out);
      }
    }
    invalid += batch.flush(cloud, orient, out);
  }
  out.invalid = invalid;
}

}  // namespace upd::core
