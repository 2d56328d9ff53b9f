#include "upd/core/fast_normals.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "fast_cell_map.h"
#include "fast_simd.h"
#include "upd/core/openmp.h"

namespace upd {

namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Coordinate of the invalid pixels in the scanned images: farther than any radius [m].
constexpr float kFar = 1e18f;

// Moments of a set of points relative to a reference: count, sum q, sum q q^T (upper).
struct Moments {
  double n = 0, x = 0, y = 0, z = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
};

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

// normalFromUnitCovariance for count covariances at once (cov[k][i]: entry k of the i-th), in
// float vector lanes, for the common case of a plane: where l1 >= 2 l0, nine products with B
// leave an error below (1/2)^20 rad, 1e-6, the float precision. Elsewhere (l1 < 2 l0: no clear
// plane; or a degenerate covariance) plane[i] = 0 and the lane's output is to be ignored: the
// caller takes normalFromUnitCovariance, whose general eigen solver decides.
UPD_VECTOR_CLONES
void planeNormals(const double* __restrict a_, const double* __restrict b_,
                  const double* __restrict c_, const double* __restrict d_,
                  const double* __restrict e_, const double* __restrict f_, std::size_t count,
                  float* __restrict nx, float* __restrict ny, float* __restrict nz,
                  float* __restrict curvature, std::uint8_t* __restrict plane) {
  for (std::size_t i = 0; i < count; ++i) {
    const auto a = static_cast<float>(a_[i]), b = static_cast<float>(b_[i]),
               c = static_cast<float>(c_[i]), d = static_cast<float>(d_[i]),
               e = static_cast<float>(e_[i]), f = static_cast<float>(f_[i]);
    const float A00 = d * f - e * e, A01 = c * e - b * f, A02 = b * e - c * d;
    const float A11 = a * f - c * c, A12 = b * c - a * e, A22 = a * d - b * b;
    const float adj_norm2 =
        A00 * A00 + A11 * A11 + A22 * A22 + 2.f * (A01 * A01 + A02 * A02 + A12 * A12);
    const float B00 = A00 * A00 + A01 * A01 + A02 * A02;
    const float B01 = A00 * A01 + A01 * A11 + A02 * A12;
    const float B02 = A00 * A02 + A01 * A12 + A02 * A22;
    const float B11 = A01 * A01 + A11 * A11 + A12 * A12;
    const float B12 = A01 * A02 + A11 * A12 + A12 * A22;
    const float B22 = A02 * A02 + A12 * A12 + A22 * A22;
    const bool col0 = B00 >= B11 && B00 >= B22, col1 = !col0 && B11 >= B22;
    float vx = col0 ? B00 : col1 ? B01 : B02;
    float vy = col0 ? B01 : col1 ? B11 : B12;
    float vz = col0 ? B02 : col1 ? B12 : B22;
    for (int it = 0; it < 9; ++it) {
      // Normalized at every step: float has less room than double.
      const float wx = B00 * vx + B01 * vy + B02 * vz;
      const float wy = B01 * vx + B11 * vy + B12 * vz;
      const float wz = B02 * vx + B12 * vy + B22 * vz;
      const float k = 1.f / std::sqrt(wx * wx + wy * wy + wz * wz);
      vx = wx * k, vy = wy * k, vz = wz * k;
    }
    const float q0 = vx * (a * vx + b * vy + c * vz) + vy * (b * vx + d * vy + e * vz) +
                     vz * (c * vx + e * vy + f * vz);
    // l1 and l2 from their sum 1 - l0 and their product, v's Rayleigh quotient of adj(C) (v is
    // its eigenvector of eigenvalue l1 l2): l1 = 2 p / (sum + sqrt(sum^2 - 4 p)), a form
    // without the cancellation that float would suffer on a flat surface (l0 ~ 1e-6).
    const float p = vx * (A00 * vx + A01 * vy + A02 * vz) + vy * (A01 * vx + A11 * vy + A12 * vz) +
                    vz * (A02 * vx + A12 * vy + A22 * vz);
    const float sum = 1.f - q0;
    const float l1 = 2.f * p / (sum + std::sqrt(std::max(0.f, sum * sum - 4.f * p)));
    const bool finite = vx == vx && vy == vy && vz == vz && l1 == l1;
    plane[i] = adj_norm2 > 1e-20f && l1 >= 2.f * q0 && finite ? 1 : 0;
    nx[i] = vx, ny[i] = vy, nz[i] = vz;
    curvature[i] = std::max(0.f, q0);  // lambda_0 / trace
  }
}

inline void setUnset(Normals& out, std::size_t i) {
  out.nx[i] = out.ny[i] = out.nz[i] = out.curvature[i] = kNaN;
}

inline void setNormal(Normals& out, std::size_t i, const Eigen::Vector3f& n, float curvature) {
  out.nx[i] = n.x();
  out.ny[i] = n.y();
  out.nz[i] = n.z();
  out.curvature[i] = curvature;
}

// Pixels [begin, end): their range from the sensor origin, and their coordinates relative to
// ref as scan images (NaN range and kFar coordinates where the point is not finite).
UPD_VECTOR_CLONES
void scanImages(const float* __restrict x, const float* __restrict y, const float* __restrict z,
                const Eigen::Vector3f& origin, const Eigen::Vector3f& ref, std::size_t begin,
                std::size_t end, float* __restrict range, float* __restrict X, float* __restrict Y,
                float* __restrict Z) {
  const float ox = origin.x(), oy = origin.y(), oz = origin.z();
  const float rx = ref.x(), ry = ref.y(), rz = ref.z();
  for (std::size_t i = begin; i < end; ++i) {
    const float dx = x[i] - ox, dy = y[i] - oy, dz = z[i] - oz;
    const float rho = std::sqrt(dx * dx + dy * dy + dz * dz);  // NaN for a non-finite point
    const bool valid = (rho > 0.f) & (rho <= std::numeric_limits<float>::max());
    range[i] = valid ? rho : kNaN;
    X[i] = valid ? x[i] - rx : kFar;
    Y[i] = valid ? y[i] - ry : kFar;
    Z[i] = valid ? z[i] - rz : kFar;
  }
}

// The chord between the unit rays of pixels i and i + step, i = first + t * step, for t in
// [0, n): the angle between them to 1e-6 at these sizes; NaN where either has no range.
UPD_VECTOR_CLONES
void lineChords(const float* __restrict x, const float* __restrict y, const float* __restrict z,
                const float* __restrict range, std::size_t first, std::size_t step, std::size_t n,
                const Eigen::Vector3f& origin, float* __restrict chord) {
  const float ox = origin.x(), oy = origin.y(), oz = origin.z();
  for (std::size_t t = 0; t < n; ++t) {
    const std::size_t i = first + t * step, j = i + step;
    const float inv_i = 1.f / range[i], inv_j = 1.f / range[j];
    const float dx = (x[i] - ox) * inv_i - (x[j] - ox) * inv_j;
    const float dy = (y[i] - oy) * inv_i - (y[j] - oy) * inv_j;
    const float dz = (z[i] - oz) * inv_i - (z[j] - oz) * inv_j;
    chord[t] = std::sqrt(dx * dx + dy * dy + dz * dz);
  }
}

// The angular pitch of the sensor per column (along_u: the angle between the rays of columns
// u and u + 1) or per row [rad]: the smallest over every 16th line, so that windows sized from
// it hold the whole ball even where the pitch shrinks (off-axis, by cos^2 of the angle for a
// pinhole camera). Columns without a sample take the median; a pitch below half the median
// (duplicated pixels) is raised to it. Empty when too few pairs are valid.
std::vector<float> pitchProfile(const PointCloud& cloud, const float* range, bool along_u) {
  const std::size_t W = cloud.width, H = cloud.height;
  const std::size_t lines = along_u ? H : W, len = along_u ? W : H;
  const std::size_t sampled = (lines + 15) / 16, pairs = len - 1;
  std::vector<float> chords(sampled * pairs);
  // Each thread reads the rows of its static share of the image, as in the stages after: rows
  // are dealt out whole, columns by their pairs' rows. (Reading lines of the image that the
  // other core writes next frame made that write twice as slow.)
#pragma omp parallel
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t k0 = along_u ? sampled * me / team : 0,
                      k1 = along_u ? sampled * (me + 1) / team : sampled;
    const std::size_t t0 = along_u ? 0 : pairs * me / team,
                      t1 = along_u ? pairs : pairs * (me + 1) / team;
    for (std::size_t k = k0; k < k1; ++k) {
      const std::size_t l = 16 * k;
      lineChords(cloud.x.data(), cloud.y.data(), cloud.z.data(), range,
                 along_u ? l * W : l + t0 * W, along_u ? 1 : W, t1 - t0, cloud.sensor_origin,
                 &chords[k * pairs + t0]);
    }
  }
  std::vector<float> lowest(len, std::numeric_limits<float>::infinity());
  std::vector<float> all;
  all.reserve(chords.size());
  for (std::size_t k = 0; k < sampled; ++k) {
    for (std::size_t t = 0; t < pairs; ++t) {
      const float a = chords[k * pairs + t];
      if (!(a == a)) continue;
      lowest[t] = std::min(lowest[t], a);
      all.push_back(a);
    }
  }
  if (all.size() < 16) return {};
  auto mid = all.begin() + static_cast<std::ptrdiff_t>(all.size() / 2);
  std::nth_element(all.begin(), mid, all.end());
  const float median = *mid;
  if (!(median > 0.f)) return {};
  for (float& p : lowest) p = std::isfinite(p) ? std::max(p, 0.5f * median) : median;
  return lowest;
}

// Largest half-width of a scanned window [pixels]; windows wider than
// NormalParams::fast_scan_px are sampled every 2nd or 4th row and column.
constexpr std::ptrdiff_t kMaxHalf = 96;

// kScanLanes floats as one GCC vector: the compiler emits AVX-512, AVX2 or SSE code for it in the
// respective UPD_VECTOR_CLONES version of a function (no intrinsics, no -march).
constexpr int kScanLanes = 8;
typedef float LaneF __attribute__((vector_size(kScanLanes * sizeof(float))));

typedef int LaneI __attribute__((vector_size(kScanLanes * sizeof(int))));
static_assert(kScanLanes == 8, "the shuffles below pick 8 lanes");

inline void loadLanes(LaneF& v, const float* p) { std::memcpy(&v, p, sizeof v); }
// Moments, relative to p, of the points within sqrt(radius2) of p among rows [v0, v1] (every
// row_step-th) and columns [a0, a1] of the coordinate images (row stride W). Non-finite pixels
// hold kFar, so they fail the distance test like any far point; the columns read past a1 (a
// vector at a time) are real points of the cloud or kFar padding, and the ones within the
// radius are neighbours of p like any other (the window only bounds the ball).
UPD_VECTOR_CLONES
Moments gatedMoments(const float* X, const float* Y, const float* Z, std::size_t W,
                     std::ptrdiff_t v0, std::ptrdiff_t v1, std::ptrdiff_t a0, std::ptrdiff_t a1,
                     std::ptrdiff_t row_step, float px, float py, float pz, float radius2) {
  const LaneF zero = {}, one = zero + 1.f;
  LaneF n = zero, sx = zero, sy = zero, sz = zero, sxx = zero, sxy = zero, sxz = zero, syy = zero,
        syz = zero, szz = zero;
  for (std::ptrdiff_t b = v0; b <= v1; b += row_step) {
    const std::size_t row = static_cast<std::size_t>(b) * W;
    for (std::ptrdiff_t a = a0; a <= a1; a += kScanLanes) {
      const std::size_t at = row + static_cast<std::size_t>(a);
      LaneF x, y, z;
      loadLanes(x, X + at), loadLanes(y, Y + at), loadLanes(z, Z + at);
      const LaneF qx = x - px, qy = y - py, qz = z - pz;
      const LaneF d2 = qx * qx + qy * qy + qz * qz;
      const LaneF w = d2 <= radius2 ? one : zero;
      const LaneF cx = w * qx, cy = w * qy, cz = w * qz;
      n += w, sx += cx, sy += cy, sz += cz;
      sxx += cx * qx, sxy += cx * qy, sxz += cx * qz, syy += cy * qy, syz += cy * qz,
          szz += cz * qz;
    }
  }
  const auto total = [](const LaneF& v) {
    float s[4] = {0, 0, 0, 0};
    for (int l = 0; l < kScanLanes; ++l) s[l % 4] += v[l];
    return static_cast<double>((s[0] + s[1]) + (s[2] + s[3]));
  };
  Moments m;
  m.n = total(n), m.x = total(sx), m.y = total(sy), m.z = total(sz);
  m.xx = total(sxx), m.xy = total(sxy), m.xz = total(sxz);
  m.yy = total(syy), m.yz = total(syz), m.zz = total(szz);
  return m;
}

struct OrientConstants {
  float ox, oy, oz;  // sensor origin
  float ux, uy, uz;  // unit up
  float sin_band;
};

// One row of pass 2, as a vector loop: pixel u takes the normal of its block's centre
// (block[k * W + u], k = 0..4: normal x, y, z, curvature, centre range) when its range
// is within jump * range of the centre's, oriented as NormalOrienter does, and taken[u] says so
// (a NaN range or centre fails the test). The others get NaN here.
UPD_VECTOR_CLONES
void shareBlockNormals(const float* __restrict range, const float* __restrict x,
                       const float* __restrict y, const float* __restrict z,
                       const float* __restrict block, std::size_t W, float jump,
                       const OrientConstants& c, float* __restrict nx, float* __restrict ny,
                       float* __restrict nz, float* __restrict curvature,
                       std::uint8_t* __restrict taken) {
  const float* __restrict bnx = block;
  const float* __restrict bny = block + W;
  const float* __restrict bnz = block + 2 * W;
  const float* __restrict bcurv = block + 3 * W;
  const float* __restrict brange = block + 4 * W;
  for (std::size_t u = 0; u < W; ++u) {
    const float rho = range[u];
    const bool good = std::fabs(brange[u] - rho) <= jump * rho;
    const float bx = bnx[u], by = bny[u], bz = bnz[u];
    const float along_up = bx * c.ux + by * c.uy + bz * c.uz;
    const float towards = bx * (c.ox - x[u]) + by * (c.oy - y[u]) + bz * (c.oz - z[u]);
    const bool keep = std::fabs(along_up) > c.sin_band ? along_up > 0.f : towards >= 0.f;
    const float sign = keep ? 1.f : -1.f;
    nx[u] = good ? sign * bx : kNaN;
    ny[u] = good ? sign * by : kNaN;
    nz[u] = good ? sign * bz : kNaN;
    curvature[u] = good ? bcurv[u] : kNaN;
    taken[u] = good ? 1 : 0;
  }
}

}  // namespace

bool organizedNormalsApply(const PointCloud& cloud, const NormalParams& params) {
  return cloud.isOrganized() && params.knn == 0 &&
         params.weighting == NormalWeighting::Uniform;
}

Normals computeNormalsOrganized(const PointCloud& cloud, const NormalParams& params,
                                const Eigen::Vector3f& up) {
  Normals out;
  computeNormalsOrganized(cloud, params, up, out);
  return out;
}

void computeNormalsOrganized(const PointCloud& cloud, const NormalParams& params,
                             const Eigen::Vector3f& up, Normals& out) {
  params.validate();
  if (!organizedNormalsApply(cloud, params)) {
    throw std::invalid_argument(
        "computeNormalsOrganized: needs an organized cloud (height > 1), NormalParams.knn = 0 "
        "and NormalParams.weighting = uniform");
  }
  const std::size_t W = cloud.width, H = cloud.height, N = cloud.size();
  // Every pixel's normal is written below (a normal or NaN): no fill, and the caller's
  // buffers are reused from frame to frame.
  out.nx.resize(N), out.ny.resize(N), out.nz.resize(N), out.curvature.resize(N);
  out.invalid = 0;
  std::size_t first = 0;
  while (first < N && !cloud.isFinite(first)) ++first;
  if (first == N) {
    out = Normals::unset(N);
    out.invalid = N;
    return;
  }
  const auto Wi = static_cast<std::ptrdiff_t>(W), Hi = static_cast<std::ptrdiff_t>(H);
  // Points relative to the first finite one (float differences stay exact far from the
  // origin), kFar where invalid and as padding (a vector of lanes may read past the last row),
  // and the range of every pixel from the sensor.
  const Eigen::Vector3f ref = cloud.point(first);
  const Eigen::Vector3f origin = cloud.sensor_origin;
  // The calling thread's buffers, kept for the next frame and shared by the team (their
  // pointers are taken here, outside the parallel regions).
  static thread_local std::vector<float> buffer, range_buffer;
  const std::size_t image_len = N + kMaxHalf + kScanLanes;
  buffer.resize(3 * image_len);
  range_buffer.resize(N);
  float* const X = buffer.data();
  float* const Y = X + image_len;
  float* const Z = Y + image_len;
  float* const range = range_buffer.data();
  for (float* pad : {X + N, Y + N, Z + N}) std::fill(pad, pad + (image_len - N), kFar);
  constexpr std::size_t kRows = 8192;  // pixels per task
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t t = 0; t < static_cast<std::ptrdiff_t>((N + kRows - 1) / kRows); ++t) {
    const std::size_t begin = static_cast<std::size_t>(t) * kRows;
    scanImages(cloud.x.data(), cloud.y.data(), cloud.z.data(), origin, ref, begin,
               std::min(N, begin + kRows), range, X, Y, Z);
  }
  // Every 2nd and every 4th column of the coordinate images, as images of their own (all the
  // rows, kFar padding after the last): a window scanned every s-th column reads them whole
  // vectors at a time.
  static thread_local std::vector<float> sparse_buffer;
  const std::size_t W2 = (W + 1) / 2, W4 = (W + 3) / 4;
  const std::size_t len2 = H * W2 + kScanLanes, len4 = H * W4 + kScanLanes;
  sparse_buffer.resize(3 * (len2 + len4));
  float* const X2 = sparse_buffer.data();
  float* const X4 = X2 + 3 * len2;
  for (int k = 0; k < 3; ++k) {
    std::fill(X2 + k * len2 + H * W2, X2 + (k + 1) * len2, kFar);
    std::fill(X4 + k * len4 + H * W4, X4 + (k + 1) * len4, kFar);
  }
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t v = 0; v < Hi; ++v) {
    const auto row = static_cast<std::size_t>(v);
    for (int k = 0; k < 3; ++k) {
      const float* __restrict from = X + k * image_len + row * W;
      float* __restrict to2 = X2 + k * len2 + row * W2;
      float* __restrict to4 = X4 + k * len4 + row * W4;
      for (std::size_t c = 0; c < W2; ++c) to2[c] = from[2 * c];
      for (std::size_t c = 0; c < W4; ++c) to4[c] = from[4 * c];
    }
  }
  const std::vector<float> pitch_u = pitchProfile(cloud, range, true);
  const std::vector<float> pitch_v = pitchProfile(cloud, range, false);
  if (pitch_u.empty() || pitch_v.empty()) {
    // Not a central projection we can measure (too few neighbouring valid pixels, or all rays
    // equal): the hash grid finds the same neighbours.
    out = computeNormalsGrid(cloud, params, up);
    return;
  }

  // The ball of radius r around a point at range rho subtends asin(r / rho) each way: its
  // pixels lie within that angle over the pitch of their column and row, plus one. Those
  // windows are scanned and the points within r in 3D kept: the neighbours of the exact path.
  // A window wider than fast_scan_px pixels (a near point) is scanned every 2nd row and column,
  // one wider than twice that every 4th: a regular sample of its ball, still hundreds of
  // points.
  const double radius = params.radius_m;
  const std::ptrdiff_t scan_px = params.fast_scan_px;
  const auto radius2 = static_cast<float>(radius * radius);
  const auto scanMoments = [&](std::ptrdiff_t u, std::ptrdiff_t v, std::size_t i) {
    const double angle = std::asin(std::min(1.0, radius / range[i]));
    const auto eu = std::min<std::ptrdiff_t>(
        kMaxHalf, static_cast<std::ptrdiff_t>(angle / pitch_u[static_cast<std::size_t>(u)]) + 1);
    const auto ev = std::min<std::ptrdiff_t>(
        kMaxHalf, static_cast<std::ptrdiff_t>(angle / pitch_v[static_cast<std::size_t>(v)]) + 1);
    // Every stride-th row and column: every one up to fast_scan_px pixels across, every 2nd up
    // to twice that, every 4th beyond; the columns of the sparse images, the window's first one
    // rounded down to them.
    const std::ptrdiff_t side = 2 * std::max(eu, ev) + 1;
    const std::ptrdiff_t stride = side <= scan_px ? 1 : side <= 2 * scan_px ? 2 : 4;
    const std::ptrdiff_t v0 = std::max<std::ptrdiff_t>(0, v - ev);
    const std::ptrdiff_t v1 = std::min<std::ptrdiff_t>(Hi - 1, v + ev);
    const std::ptrdiff_t a0 = std::max<std::ptrdiff_t>(0, u - eu) / stride;
    const std::ptrdiff_t a1 = std::min<std::ptrdiff_t>(Wi - 1, u + eu) / stride;
    if (stride == 1) {
      return gatedMoments(X, Y, Z, W, v0, v1, a0, a1, 1, X[i], Y[i], Z[i], radius2);
    }
    const float* const S = stride == 2 ? X2 : X4;
    const std::size_t len = stride == 2 ? len2 : len4;
    return gatedMoments(S, S + len, S + 2 * len, stride == 2 ? W2 : W4, v0, v1, a0, a1, stride,
                        X[i], Y[i], Z[i], radius2);
  };
  // A normal is computed at the centre of every block of D x D pixels (pass 1). A pixel takes
  // the normal of the nearest block centre on its surface (ranges within max_depth_jump_ratio
  // of each other): its own block's, else the closest in range of the 8 blocks around it; a
  // pixel with no such centre (a thin object, a depth edge) computes its own (pass 2).
  const std::ptrdiff_t D = params.fast_block_px;
  const std::ptrdiff_t BW = (Wi + D - 1) / D, BH = (Hi + D - 1) / D;
  const auto n_blocks = static_cast<std::size_t>(BW * BH);
  const NormalOrienter orient(origin, up, params.vertical_band_rad);
  const float jump = static_cast<float>(params.max_depth_jump_ratio);
  static thread_local std::vector<float> block_buffer;
  block_buffer.assign(5 * n_blocks, kNaN);
  float* const bn = block_buffer.data();  // per block: nx, ny, nz, curvature, centre range
  // The centre pixel of block (bu, bv) along u or v (clamped to the image).
  const auto centreU = [&](std::ptrdiff_t bu) { return std::min(Wi - 1, bu * D + D / 2); };
  const auto centreV = [&](std::ptrdiff_t bv) { return std::min(Hi - 1, bv * D + D / 2); };
  // Pass 1, in tasks of kTask blocks: the moments of each centre's ball, then the normals of
  // the task's clear planes at once (planeNormals, vector lanes), then the rest one by one.
  constexpr std::size_t kTask = 64;
  // (Dynamic: a near block's window holds many more pixels than a far one's. It reads the
  // images and writes only the block table; pass 2, which writes every pixel, is static.)
#pragma omp parallel for schedule(dynamic, 1)
  for (std::ptrdiff_t t = 0; t < static_cast<std::ptrdiff_t>((n_blocks + kTask - 1) / kTask); ++t) {
    const std::size_t b0 = static_cast<std::size_t>(t) * kTask;
    const std::size_t count = std::min(kTask, n_blocks - b0);
    double cov[6][kTask];
    float nx[kTask], ny[kTask], nz[kTask], curv[kTask];
    std::uint8_t has_cov[kTask], plane[kTask];
    for (std::size_t j = 0; j < count; ++j) {
      const auto b = static_cast<std::ptrdiff_t>(b0 + j);
      const std::ptrdiff_t cu = centreU(b % BW), cv = centreV(b / BW);
      const std::size_t ci = static_cast<std::size_t>(cv) * W + static_cast<std::size_t>(cu);
      double c[6] = {1, 0, 0, 0, 0, 0};  // (a placeholder where there is none)
      has_cov[j] = range[ci] == range[ci] && [&] {
        const Moments m = scanMoments(cu, cv, ci);
        return m.n >= 3 && unitCovariance(m, c);
      }();
      for (int k = 0; k < 6; ++k) cov[k][j] = c[k];
    }
    planeNormals(cov[0], cov[1], cov[2], cov[3], cov[4], cov[5], count, nx, ny, nz, curv, plane);
    for (std::size_t j = 0; j < count; ++j) {
      if (!has_cov[j]) continue;
      const std::size_t b = b0 + j;
      Eigen::Vector3f n(nx[j], ny[j], nz[j]);
      float curvature = curv[j];
      if (!plane[j]) {
        const double c[6] = {cov[0][j], cov[1][j], cov[2][j], cov[3][j], cov[4][j], cov[5][j]};
        if (!normalFromUnitCovariance(c, n, curvature)) continue;
      }
      const auto bb = static_cast<std::ptrdiff_t>(b);
      const std::size_t ci = static_cast<std::size_t>(centreV(bb / BW)) * W +
                             static_cast<std::size_t>(centreU(bb % BW));
      float* const o = bn + 5 * b;
      o[0] = n.x(), o[1] = n.y(), o[2] = n.z(), o[3] = curvature, o[4] = range[ci];
    }
  }
  // Pass 2. The common case, a pixel on its own block centre's surface, runs as a vector loop
  // per row (shareBlockNormals, reading its block row spread out to one value per column); the
  // others (no valid range, a depth edge, a failed centre) then go through the general rule.
  const OrientConstants oc{origin.x(), origin.y(), origin.z(),     up.x(),
                           up.y(),     up.z(),     orient.sin_band};
  // The pixels that need a scan of their own (no block centre on their surface) gather in
  // per-thread lists and are scanned after the rows, shared out dynamically: they cluster at
  // depth edges, and a static share of them left one thread with most of the work.
  std::size_t invalid = 0;
  std::vector<std::vector<std::uint32_t>> own_scan(static_cast<std::size_t>(openmp::maxThreads()));
  std::vector<std::uint32_t> to_scan;
#pragma omp parallel reduction(+ : invalid)
  {
    std::vector<std::uint8_t> taken(W);
    std::vector<float> spread(5 * W);
    std::vector<std::uint32_t>& my_scan = own_scan[static_cast<std::size_t>(openmp::threadIndex())];
#pragma omp for schedule(static)
    for (std::ptrdiff_t bv = 0; bv < BH; ++bv) {
      for (std::size_t u = 0; u < W; ++u) {
        const float* b = bn + 5 * (bv * BW + static_cast<std::ptrdiff_t>(u) / D);
        for (std::size_t k = 0; k < 5; ++k) spread[k * W + u] = b[k];
      }
      for (std::ptrdiff_t v = bv * D; v < std::min(Hi, bv * D + D); ++v) {
        const std::size_t row = static_cast<std::size_t>(v) * W;
        shareBlockNormals(range + row, cloud.x.data() + row, cloud.y.data() + row,
                          cloud.z.data() + row, spread.data(), W, jump, oc, out.nx.data() + row,
                          out.ny.data() + row, out.nz.data() + row, out.curvature.data() + row,
                          taken.data());
        for (std::ptrdiff_t u = 0; u < Wi; ++u) {
          if (taken[static_cast<std::size_t>(u)]) continue;
          const std::size_t i = row + static_cast<std::size_t>(u);
          const float rho = range[i];
          if (!(rho == rho)) {
            setUnset(out, i);
            ++invalid;
            continue;
          }
          const std::ptrdiff_t bu = u / D;
          const float tolerance = jump * rho;
          const float* pick = bn + 5 * (bv * BW + bu);
          const bool is_centre = u == centreU(bu) && v == centreV(bv);
          if (is_centre && !(pick[4] == pick[4])) {  // its own scan found no plane
            setUnset(out, i);
            ++invalid;
            continue;
          }
          if (!(std::abs(pick[4] - rho) <= tolerance)) {  // NaN (no normal there) fails too
            pick = nullptr;
            float best = tolerance;
            for (std::ptrdiff_t dv = std::max<std::ptrdiff_t>(0, bv - 1);
                 dv <= std::min(BH - 1, bv + 1); ++dv) {
              for (std::ptrdiff_t du = std::max<std::ptrdiff_t>(0, bu - 1);
                   du <= std::min(BW - 1, bu + 1); ++du) {
                const float* c = bn + 5 * (dv * BW + du);
                const float d = std::abs(c[4] - rho);
                if (d <= best) best = d, pick = c;
              }
            }
          }
          if (pick == nullptr) {
            my_scan.push_back(static_cast<std::uint32_t>(i));
            continue;
          }
          setNormal(out, i, orient(Eigen::Vector3f(pick[0], pick[1], pick[2]), cloud.point(i)),
                    pick[3]);
        }
      }
    }
#pragma omp single
    {
      for (const auto& list : own_scan) to_scan.insert(to_scan.end(), list.begin(), list.end());
    }
#pragma omp for schedule(dynamic, 16)
    for (std::ptrdiff_t k = 0; k < static_cast<std::ptrdiff_t>(to_scan.size()); ++k) {
      const std::size_t i = to_scan[static_cast<std::size_t>(k)];
      const auto u = static_cast<std::ptrdiff_t>(i % W), v = static_cast<std::ptrdiff_t>(i / W);
      Eigen::Vector3f n;
      float curvature;
      const Moments m = scanMoments(u, v, i);
      if (!(m.n >= 3 && normalFromMoments(m, n, curvature))) {
        setUnset(out, i);
        ++invalid;
        continue;
      }
      setNormal(out, i, orient(n, cloud.point(i)), curvature);
    }
  }
  out.invalid = invalid;
}

Normals computeNormalsGrid(const PointCloud& cloud, const NormalParams& params,
                           const Eigen::Vector3f& up) {
  params.validate();
  requireParam(params.knn == 0, "NormalParams", "knn", params.knn,
               "computeNormalsGrid finds radius neighbourhoods: it needs knn = 0");
  const std::size_t N = cloud.size();
  Normals out = Normals::unset(N);
  std::size_t first = 0;
  while (first < N && !cloud.isFinite(first)) ++first;
  if (first == N) {
    out.invalid = N;
    return out;
  }
  // Cells of edge radius_m: the neighbours of a point lie in the 27 cells around its own.
  // Points are sorted by cell (counting sort) and kept relative to the first finite point.
  const Eigen::Vector3d ref = cloud.point(first).cast<double>();
  const double inv = 1.0 / params.radius_m;
  detail::CellMap map(N / 8 + 64);
  std::vector<std::int32_t> cell_xyz;
  std::vector<std::uint32_t> cell_of(N, detail::kNoIndex);
  for (std::size_t i = first; i < N; ++i) {
    if (!cloud.isFinite(i)) continue;
    const Eigen::Vector3d g = (cloud.point(i).cast<double>() - ref) * inv;
    const std::int64_t x = detail::floorToInt(g.x()), y = detail::floorToInt(g.y()),
                       z = detail::floorToInt(g.z());
    if (!detail::keyFits(x, y, z)) {
      throw std::invalid_argument("NormalParams.radius_m = " + std::to_string(params.radius_m) +
                                  ": the cloud spans more than 2^20 radii along an axis");
    }
    bool inserted = false;
    cell_of[i] = map.findOrInsert(detail::packKey(x, y, z), inserted);
    if (inserted) {
      cell_xyz.insert(cell_xyz.end(), {static_cast<std::int32_t>(x), static_cast<std::int32_t>(y),
                                       static_cast<std::int32_t>(z)});
    }
  }
  const std::size_t n_cells = cell_xyz.size() / 3;
  std::vector<std::uint32_t> start(n_cells + 1, 0);
  for (std::size_t i = 0; i < N; ++i) {
    if (cell_of[i] != detail::kNoIndex) ++start[cell_of[i] + 1];
  }
  for (std::size_t c = 0; c < n_cells; ++c) start[c + 1] += start[c];
  std::vector<std::uint32_t> order(start.back());
  std::vector<Eigen::Vector3f> local(start.back());
  {
    std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
    for (std::size_t i = 0; i < N; ++i) {
      if (cell_of[i] == detail::kNoIndex) continue;
      const std::uint32_t slot = fill[cell_of[i]]++;
      order[slot] = static_cast<std::uint32_t>(i);
      local[slot] = (cloud.point(i).cast<double>() - ref).cast<float>();
    }
  }

  const float radius2 = static_cast<float>(params.radius_m * params.radius_m);
  const bool gaussian = params.weighting == NormalWeighting::Gaussian;
  const float sigma = 0.5f * static_cast<float>(params.radius_m);
  const float inv_2s2 = 1.f / (2.f * sigma * sigma);
  std::size_t invalid = N - start.back();
  const NormalOrienter orient(cloud.sensor_origin, up, params.vertical_band_rad);
#pragma omp parallel reduction(+ : invalid)
  {
    // The candidates of the points of a cell (the points of the 27 cells around it), as
    // coordinate rows for gatedMoments, padded with kFar.
    std::vector<float> cx, cy, cz;
#pragma omp for schedule(dynamic, 16)
    for (std::ptrdiff_t cc = 0; cc < static_cast<std::ptrdiff_t>(n_cells); ++cc) {
      const auto c = static_cast<std::size_t>(cc);
      std::array<std::uint32_t, 27> around{};
      int n_around = 0;
      for (int d = 0; d < 27; ++d) {
        const std::uint32_t id = map.find(detail::packKey(cell_xyz[3 * c] + d % 3 - 1,
                                                          cell_xyz[3 * c + 1] + (d / 3) % 3 - 1,
                                                          cell_xyz[3 * c + 2] + d / 9 - 1));
        if (id != detail::kNoIndex) around[n_around++] = id;
      }
      cx.clear(), cy.clear(), cz.clear();
      for (int a = 0; a < n_around; ++a) {
        for (std::uint32_t t = start[around[a]]; t < start[around[a] + 1]; ++t) {
          cx.push_back(local[t].x()), cy.push_back(local[t].y()), cz.push_back(local[t].z());
        }
      }
      const auto n_candidates = static_cast<std::ptrdiff_t>(cx.size());
      cx.resize(cx.size() + kScanLanes, kFar), cy.resize(cx.size(), kFar),
          cz.resize(cx.size(), kFar);
      for (std::uint32_t s = start[c]; s < start[c + 1]; ++s) {
        const Eigen::Vector3f p = local[s];
        // Moments of the neighbours relative to p (eq. 4), weighted when Gaussian.
        Moments m;
        std::size_t count = 0;
        if (!gaussian) {
          m = gatedMoments(cx.data(), cy.data(), cz.data(), cx.size(), 0, 0, 0, n_candidates - 1,
                           1, p.x(), p.y(), p.z(), radius2);
          count = static_cast<std::size_t>(m.n);
        } else {
          for (std::ptrdiff_t t = 0; t < n_candidates; ++t) {
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
        }
        Eigen::Vector3f n;
        float curvature;
        const std::size_t i = order[s];
        if (count < 3 || !normalFromMoments(m, n, curvature)) {
          ++invalid;
          continue;
        }
        setNormal(out, i, orient(n, cloud.point(i)), curvature);
      }
    }
  }
  out.invalid = invalid;
  return out;
}

}  // namespace upd
