// The organized path of the fast normals, computeNormalsOrganized: a normal per block of pixels
// from the points within the radius in an image window around the block's centre (pass 1),
// shared by the pixels on the centre's surface; the others scan windows of their own (pass 2).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "chunk_deal.h"
#include "fast_normals_internal.h"
#include "upd/core/fast_normals.h"
#include "upd/core/openmp.h"

namespace upd::core {

namespace {

using detail::kFar;
using detail::kNaN;
using detail::kScanLanes;
using detail::Moments;

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

// Largest half-width of a scanned window [pixels]; windows wider than
// NormalParams::fast_scan_px are sampled every 2nd or 4th row and column.
constexpr std::ptrdiff_t kMaxHalf = 96;

struct OrientConstants {
  float ox, oy, oz;  // sensor origin
  float ux, uy, uz;  // unit up
  float sin_band;
};

// One row of pass 2, as a vector loop: pixel u takes the normal of its block's centre
// (block[k * W + u], k = 0..4: normal x, y, z, curvature, centre range) when its range
// is within jump * range of the centre's, oriented as NormalOrienter does (a NaN range or
// centre fails the test). The others get NaN here; taken[u] says that pixel u is done: it took
// a normal, or it has no range (no normal). Returns the pixels without a range.
UPD_VECTOR_CLONES
std::uint32_t shareBlockNormals(const float* __restrict range, const float* __restrict x,
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
  std::uint32_t no_range = 0;
  for (std::size_t u = 0; u < W; ++u) {
    const float rho = range[u];
    const bool unranged = !(rho == rho);
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
    taken[u] = (good | unranged) ? 1 : 0;
    no_range += unranged ? 1u : 0u;
  }
  return no_range;
}

// The calling thread's images, kept for the next frame and shared by the team (their pointers
// are taken outside the parallel regions).
struct OrganizedBuffers {
  std::vector<float> xyz, range, sparse, blocks;
};

// The images the windows are scanned in: the points relative to the first finite one (float
// differences stay exact far from the origin), kFar where invalid and as padding (a vector of
// lanes may read past the last row), the range of every pixel from the sensor, and every 2nd
// and every 4th column of the coordinate images as images of their own (all the rows, kFar
// padding after the last), so that a window scanned every s-th column reads whole vectors.
struct ScanImages {
  std::size_t W = 0, H = 0, len = 0;
  float *X = nullptr, *Y = nullptr, *Z = nullptr, *range = nullptr;
  std::size_t W2 = 0, W4 = 0, len2 = 0, len4 = 0;
  float *X2 = nullptr, *X4 = nullptr;  // x, y, z images of length len2 (len4) each
};

ScanImages fillScanImages(const PointCloud& cloud, const Eigen::Vector3f& ref,
                          OrganizedBuffers& buf) {
  ScanImages im;
  const std::size_t N = cloud.size();
  im.W = cloud.width, im.H = cloud.height, im.len = N + kMaxHalf + kScanLanes;
  buf.xyz.resize(3 * im.len);
  buf.range.resize(N);
  im.X = buf.xyz.data(), im.Y = im.X + im.len, im.Z = im.Y + im.len;
  im.range = buf.range.data();
  for (float* pad : {im.X + N, im.Y + N, im.Z + N}) std::fill(pad, pad + (im.len - N), kFar);
  constexpr std::size_t kRows = 8192;  // pixels per task
  const Eigen::Vector3f origin = cloud.sensor_origin;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t t = 0; t < static_cast<std::ptrdiff_t>((N + kRows - 1) / kRows); ++t) {
    const std::size_t begin = static_cast<std::size_t>(t) * kRows;
    scanImages(cloud.x.data(), cloud.y.data(), cloud.z.data(), origin, ref, begin,
               std::min(N, begin + kRows), im.range, im.X, im.Y, im.Z);
  }
  return im;
}

void fillSparseColumns(ScanImages& im, OrganizedBuffers& buf) {
  const std::size_t W = im.W, H = im.H;
  im.W2 = (W + 1) / 2, im.W4 = (W + 3) / 4;
  im.len2 = H * im.W2 + kScanLanes, im.len4 = H * im.W4 + kScanLanes;
  const std::size_t W2 = im.W2, W4 = im.W4, len2 = im.len2, len4 = im.len4;
  buf.sparse.resize(3 * (len2 + len4));
  float* const X2 = im.X2 = buf.sparse.data();
  float* const X4 = im.X4 = X2 + 3 * len2;
  for (int k = 0; k < 3; ++k) {
    std::fill(X2 + k * len2 + H * W2, X2 + (k + 1) * len2, kFar);
    std::fill(X4 + k * len4 + H * W4, X4 + (k + 1) * len4, kFar);
  }
  const float* const X = im.X;
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t v = 0; v < static_cast<std::ptrdiff_t>(H); ++v) {
    const auto row = static_cast<std::size_t>(v);
    for (int k = 0; k < 3; ++k) {
      const float* __restrict from = X + k * im.len + row * W;
      float* __restrict to2 = X2 + k * len2 + row * W2;
      float* __restrict to4 = X4 + k * len4 + row * W4;
      for (std::size_t c = 0; c < W2; ++c) to2[c] = from[2 * c];
      for (std::size_t c = 0; c < W4; ++c) to4[c] = from[4 * c];
    }
  }
}

// The moments of the ball of radius r around a pixel. The ball around a point at range rho
// subtends asin(r / rho) each way: its pixels lie within that angle over the pitch of their
// column and row, plus one. That window is scanned and the points within r in 3D kept: the
// neighbours of the exact path. A window wider than fast_scan_px pixels (a near point) is
// scanned every 2nd row and column, one wider than twice that every 4th: a regular sample of
// its ball, still hundreds of points.
struct WindowScan {
  WindowScan(const ScanImages& images, const std::vector<float>& along_u,
             const std::vector<float>& along_v, double radius_m, std::ptrdiff_t scan_px_)
      : im(images),
        pitch_u(along_u),
        pitch_v(along_v),
        radius(radius_m),
        scan_px(scan_px_),
        radius2(static_cast<float>(radius_m * radius_m)) {}

  const ScanImages& im;
  const std::vector<float>& pitch_u;
  const std::vector<float>& pitch_v;
  double radius;
  std::ptrdiff_t scan_px;
  float radius2;

  Moments operator()(std::ptrdiff_t u, std::ptrdiff_t v, std::size_t i) const {
    const auto Wi = static_cast<std::ptrdiff_t>(im.W), Hi = static_cast<std::ptrdiff_t>(im.H);
    const double angle = std::asin(std::min(1.0, radius / im.range[i]));
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
    const float px = im.X[i], py = im.Y[i], pz = im.Z[i];
    if (stride == 1) {
      return detail::gatedMoments(im.X, im.Y, im.Z, im.W, v0, v1, a0, a1, 1, px, py, pz, radius2);
    }
    const float* const S = stride == 2 ? im.X2 : im.X4;
    const std::size_t len = stride == 2 ? im.len2 : im.len4;
    return detail::gatedMoments(S, S + len, S + 2 * len, stride == 2 ? im.W2 : im.W4, v0, v1, a0,
                                a1, stride, px, py, pz, radius2);
  }
};

// The blocks of D x D pixels whose centres get a normal in pass 1: per block nx, ny, nz,
// curvature and the centre's range (NaN where there is no normal).
struct BlockTable {
  std::ptrdiff_t D = 1, BW = 0, BH = 0, Wi = 0, Hi = 0;
  float* bn = nullptr;

  std::size_t size() const { return static_cast<std::size_t>(BW * BH); }
  // The centre pixel of block (bu, bv) along u or v (clamped to the image).
  std::ptrdiff_t centreU(std::ptrdiff_t bu) const { return std::min(Wi - 1, bu * D + D / 2); }
  std::ptrdiff_t centreV(std::ptrdiff_t bv) const { return std::min(Hi - 1, bv * D + D / 2); }
  std::size_t centreIndex(std::ptrdiff_t b) const {
    return static_cast<std::size_t>(centreV(b / BW)) * static_cast<std::size_t>(Wi) +
           static_cast<std::size_t>(centreU(b % BW));
  }
  const float* at(std::ptrdiff_t bu, std::ptrdiff_t bv) const { return bn + 5 * (bv * BW + bu); }
};

// Pass 1 for the task of blocks [b0, b0 + kTask) (fewer at the end): the moments of each
// centre's ball, then the normals of the clear planes at once (planeNormals, vector lanes),
// then the rest one by one.
constexpr std::size_t kTask = 64;
void blockTaskNormals(const WindowScan& scan, const BlockTable& blocks, std::size_t b0) {
  const std::size_t count = std::min(kTask, blocks.size() - b0);
  std::fill(blocks.bn + 5 * b0, blocks.bn + 5 * (b0 + count), kNaN);  // (a block without one)
  const float* const range = scan.im.range;
  double cov[6][kTask] = {};  // (only the first count are read; zeroed for -Wmaybe-uninitialized)
  float nx[kTask], ny[kTask], nz[kTask], curv[kTask];
  std::uint8_t has_cov[kTask], plane[kTask];
  for (std::size_t j = 0; j < count; ++j) {
    const auto b = static_cast<std::ptrdiff_t>(b0 + j);
    const std::ptrdiff_t cu = blocks.centreU(b % blocks.BW), cv = blocks.centreV(b / blocks.BW);
    const std::size_t ci = blocks.centreIndex(b);
    double c[6] = {1, 0, 0, 0, 0, 0};  // (a placeholder where there is none)
    has_cov[j] = range[ci] == range[ci] && [&] {
      const Moments m = scan(cu, cv, ci);
      return m.n >= 3 && detail::unitCovariance(m, c);
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
      if (!detail::normalFromUnitCovariance(c, n, curvature)) continue;
    }
    const std::size_t ci = blocks.centreIndex(static_cast<std::ptrdiff_t>(b));
    float* const o = blocks.bn + 5 * b;
    o[0] = n.x(), o[1] = n.y(), o[2] = n.z(), o[3] = curvature, o[4] = range[ci];
  }
}

void blockNormals(const WindowScan& scan, const BlockTable& blocks) {
  const std::size_t n_blocks = blocks.size();
  // (Dynamic: a near block's window holds many more pixels than a far one's. It reads the
  // images and writes only the block table; pass 2, which writes every pixel, is static.)
#pragma omp parallel for schedule(dynamic, 1)
  for (std::ptrdiff_t t = 0; t < static_cast<std::ptrdiff_t>((n_blocks + kTask - 1) / kTask); ++t) {
    const std::size_t b0 = static_cast<std::size_t>(t) * kTask;
    blockTaskNormals(scan, blocks, b0);
  }
}

// The block centre whose normal pixel (u, v) of range rho takes (block row bv): its own
// block's when within jump * rho in range, else the closest in range of the 8 around it;
// nullptr when none is.
const float* nearestCentre(const BlockTable& blocks, std::ptrdiff_t u, std::ptrdiff_t bv, float rho,
                           float jump) {
  const std::ptrdiff_t bu = u / blocks.D;
  const float tolerance = jump * rho;
  const float* pick = blocks.at(bu, bv);
  if (std::abs(pick[4] - rho) <= tolerance) return pick;  // NaN (no normal there) fails
  pick = nullptr;
  float best = tolerance;
  for (std::ptrdiff_t dv = std::max<std::ptrdiff_t>(0, bv - 1);
       dv <= std::min(blocks.BH - 1, bv + 1); ++dv) {
    for (std::ptrdiff_t du = std::max<std::ptrdiff_t>(0, bu - 1);
         du <= std::min(blocks.BW - 1, bu + 1); ++du) {
      const float* c = blocks.at(du, dv);
      const float d = std::abs(c[4] - rho);
      if (d <= best) best = d, pick = c;
    }
  }
  return pick;
}

// What pass 2 reads for every pixel.
struct PixelPass {
  const PointCloud& cloud;
  const ScanImages& im;
  const BlockTable& blocks;
  const NormalOrienter& orient;
  OrientConstants oc;
  float jump;
};

// Pass 2 for the pixels of row v (block row bv) that the vector loop left (taken[u] = 0): a
// depth edge, a failed centre. Those with no block centre on their surface go to my_scan.
// Returns the pixels left without a normal.
std::size_t rowLeftovers(const PixelPass& p, std::ptrdiff_t v, std::ptrdiff_t bv,
                         const std::uint8_t* taken, std::vector<std::uint32_t>& my_scan,
                         Normals& out) {
  const BlockTable& blocks = p.blocks;
  const std::size_t row = static_cast<std::size_t>(v) * p.im.W;
  std::size_t invalid = 0;
  constexpr std::uint64_t kAllTaken = 0x0101010101010101ull;
  for (std::ptrdiff_t u = 0; u < blocks.Wi; ++u) {
    // (Most pixels are taken: 8 of them are skipped at once.)
    std::uint64_t eight = 0;
    if (u % 8 == 0 && u + 8 <= blocks.Wi) std::memcpy(&eight, taken + u, sizeof eight);
    if (eight == kAllTaken) {
      u += 7;
      continue;
    }
    if (taken[static_cast<std::size_t>(u)]) continue;
    const std::size_t i = row + static_cast<std::size_t>(u);
    const float rho = p.im.range[i];
    const std::ptrdiff_t bu = u / blocks.D;
    const float* own = blocks.at(bu, bv);
    const bool is_centre = u == blocks.centreU(bu) && v == blocks.centreV(bv);
    if (is_centre && !(own[4] == own[4])) {  // its own scan found no plane
      detail::setUnset(out, i);
      ++invalid;
      continue;
    }
    const float* pick = nearestCentre(blocks, u, bv, rho, p.jump);
    if (pick == nullptr) {
      my_scan.push_back(static_cast<std::uint32_t>(i));
      continue;
    }
    detail::setNormal(
        out, i, p.orient(Eigen::Vector3f(pick[0], pick[1], pick[2]), p.cloud.point(i)), pick[3]);
  }
  return invalid;
}

// Pass 2 for the rows of block row bv: the common case, a pixel on its own block centre's
// surface, runs as a vector loop per row (shareBlockNormals, reading its block row spread out
// to one value per column); the others then go through rowLeftovers.
std::size_t blockRowPixels(const PixelPass& p, std::ptrdiff_t bv, std::vector<float>& spread,
                           std::vector<std::uint8_t>& taken, std::vector<std::uint32_t>& my_scan,
                           Normals& out) {
  const BlockTable& blocks = p.blocks;
  const std::size_t W = p.im.W;
  for (std::size_t u = 0; u < W; ++u) {
    const float* b = blocks.at(static_cast<std::ptrdiff_t>(u) / blocks.D, bv);
    for (std::size_t k = 0; k < 5; ++k) spread[k * W + u] = b[k];
  }
  std::size_t invalid = 0;
  const PointCloud& cloud = p.cloud;
  for (std::ptrdiff_t v = bv * blocks.D; v < std::min(blocks.Hi, bv * blocks.D + blocks.D); ++v) {
    const std::size_t row = static_cast<std::size_t>(v) * W;
    invalid += shareBlockNormals(p.im.range + row, cloud.x.data() + row, cloud.y.data() + row,
                                 cloud.z.data() + row, spread.data(), W, p.jump, p.oc,
                                 out.nx.data() + row, out.ny.data() + row, out.nz.data() + row,
                                 out.curvature.data() + row, taken.data());
    invalid += rowLeftovers(p, v, bv, taken.data(), my_scan, out);
  }
  return invalid;
}

// The normal of pixel i by a scan of its own into out; returns 1 where it has none.
std::size_t pixelNormal(const PixelPass& p, const WindowScan& scan, std::size_t i, Normals& out) {
  const std::size_t W = p.im.W;
  const auto u = static_cast<std::ptrdiff_t>(i % W), v = static_cast<std::ptrdiff_t>(i / W);
  Eigen::Vector3f n;
  float curvature;
  const Moments m = scan(u, v, i);
  if (!(m.n >= 3 && detail::normalFromMoments(m, n, curvature))) {
    detail::setUnset(out, i);
    return 1;
  }
  detail::setNormal(out, i, p.orient(n, p.cloud.point(i)), curvature);
  return 0;
}

// Pass 2. The pixels that need a scan of their own (no block centre on their surface) gather in
// per-thread lists and are scanned after the rows, dealt by ChunkDeal: they cluster at depth
// edges, and a static share of them left one thread with most of the work.
std::size_t pixelNormals(const PixelPass& p, const WindowScan& scan, Normals& out) {
  const std::size_t W = p.im.W;
  std::size_t invalid = 0;
  std::vector<std::vector<std::uint32_t>> own_scan(static_cast<std::size_t>(openmp::maxThreads()));
  std::vector<std::uint32_t> to_scan;
  detail::ChunkDeal deal;  // (a thread starts at its end of to_scan: its own rows' pixels)
#pragma omp parallel reduction(+ : invalid)
  {
    std::vector<std::uint8_t> taken(W);
    std::vector<float> spread(5 * W);
    std::vector<std::uint32_t>& my_scan = own_scan[static_cast<std::size_t>(openmp::threadIndex())];
#pragma omp for schedule(static)
    for (std::ptrdiff_t bv = 0; bv < p.blocks.BH; ++bv) {
      invalid += blockRowPixels(p, bv, spread, taken, my_scan, out);
    }
#pragma omp single
    {
      for (const auto& list : own_scan) to_scan.insert(to_scan.end(), list.begin(), list.end());
      deal.reset(to_scan.size(), 16, openmp::teamSize());
    }
    detail::ChunkDeal::Hand hand(deal, openmp::threadIndex());
    for (std::size_t b, e; hand.next(b, e);) {
      for (std::size_t k = b; k < e; ++k) invalid += pixelNormal(p, scan, to_scan[k], out);
    }
  }
  return invalid;
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
  const std::size_t N = cloud.size();
  // Every pixel's normal is written below (a normal or NaN): no fill, and the caller's
  // buffers are reused from frame to frame.
  out.nx.resize(N), out.ny.resize(N), out.nz.resize(N), out.curvature.resize(N);
  out.invalid = 0;
  const std::size_t first = firstFinite(cloud);
  if (first == N) {
    out = Normals::unset(N);
    out.invalid = N;
    return;
  }
  static thread_local OrganizedBuffers buffers;
  OrganizedBuffers& buf = buffers;
  ScanImages im = fillScanImages(cloud, cloud.point(first), buf);
  fillSparseColumns(im, buf);
  std::vector<float> pitch_u, pitch_v;
  detail::pitchProfiles(cloud, im.range, pitch_u, pitch_v);
  if (pitch_u.empty() || pitch_v.empty()) {
    // Not a central projection we can measure (too few neighbouring valid pixels, or all rays
    // equal): the hash grid finds the same neighbours.
    computeNormalsGrid(cloud, params, up, out);
    return;
  }
  const WindowScan scan(im, pitch_u, pitch_v, params.radius_m, params.fast_scan_px);
  // A normal is computed at the centre of every block of D x D pixels (pass 1). A pixel takes
  // the normal of the nearest block centre on its surface (ranges within max_depth_jump_ratio
  // of each other): its own block's, else the closest in range of the 8 blocks around it; a
  // pixel with no such centre (a thin object, a depth edge) computes its own (pass 2).
  BlockTable blocks;
  blocks.D = params.fast_block_px;
  blocks.Wi = static_cast<std::ptrdiff_t>(im.W), blocks.Hi = static_cast<std::ptrdiff_t>(im.H);
  blocks.BW = (blocks.Wi + blocks.D - 1) / blocks.D,
  blocks.BH = (blocks.Hi + blocks.D - 1) / blocks.D;
  buf.blocks.resize(5 * blocks.size());  // (each task of blockNormals fills its own)
  blocks.bn = buf.blocks.data();
  blockNormals(scan, blocks);
  const Eigen::Vector3f origin = cloud.sensor_origin;
  const NormalOrienter orient(origin, up, params.vertical_band_rad);
  const OrientConstants oc{origin.x(), origin.y(), origin.z(),     up.x(),
                           up.y(),     up.z(),     orient.sin_band};
  const PixelPass pass{cloud,  im, blocks,
                       orient, oc, static_cast<float>(params.max_depth_jump_ratio)};
  out.invalid = pixelNormals(pass, scan, out);
}

}  // namespace upd::core
