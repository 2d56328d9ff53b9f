// Private to the fast normals (fast_normals.cpp: the PCA arithmetic and the hash-grid path;
// fast_normals_organized.cpp: the image-window path; fast_normals_pitch.cpp: the sensor's
// angular pitch it sizes windows by): the moments of a neighbourhood, the normal from them,
// and the vector loop that gathers the moments of the points within a radius.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "fast_simd.h"
#include "upd/core/normals.h"
#include "upd/core/point_cloud.h"

namespace upd::core::detail {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Coordinate of the invalid pixels in the scanned images: farther than any radius [m].
constexpr float kFar = 1e18f;

// kScanLanes floats as one GCC vector: the compiler emits AVX-512, AVX2 or SSE code for it in the
// respective UPD_VECTOR_CLONES version of a function (no intrinsics, no -march).
constexpr int kScanLanes = 8;

// Moments of a set of points relative to a reference: count, sum q, sum q q^T (upper).
struct Moments {
  double n = 0, x = 0, y = 0, z = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
};

// The covariance of the moments, scaled to unit trace (a, b, c / d, e / f: its upper triangle),
// or false when it has no spread.
bool unitCovariance(const Moments& m, double (&cov)[6]);

// The unoriented PCA normal of a covariance scaled to unit trace (eqs. 4-5) and its curvature,
// or false for a neighbourhood without a plane (lambda_1 ~ 0, as pcaNormal).
bool normalFromUnitCovariance(const double (&cov)[6], Eigen::Vector3f& n, float& curvature);

// unitCovariance and normalFromUnitCovariance of count neighbourhoods' moments given as rows
// (field k of neighbourhood i at m[k * stride + i], in Moments' order n, x, y, z, xx, xy, xz,
// yy, yz, zz): ok[i] is 1 where both succeed, with n[i] and curvature[i], else 0. The same values
// bit for bit, four at a time on AVX2, eight on AVX-512.
void normalsFromMoments(const double* m, std::size_t stride, std::size_t count,
                        Eigen::Vector3f* n, float* curvature, std::uint8_t* ok);

// The same as a CPU without AVX-512 computes them (the tests compare them).
void normalsFromMomentsWithoutAvx512(const double* m, std::size_t stride, std::size_t count,
                                     Eigen::Vector3f* n, float* curvature, std::uint8_t* ok);

// The angular pitch of the sensor per column (along_u: the angle between the rays of columns
// u and u + 1) and per row [rad], from the ranges of an organized cloud
// (fast_normals_pitch.cpp); empty when too few neighbouring pixels have a range.
void pitchProfiles(const PointCloud& cloud, const float* range, std::vector<float>& along_u,
                   std::vector<float>& along_v);

// The same from the moments of a neighbourhood (m.n is the sum of the weights). The caller
// checks that there are at least 3 points.
bool normalFromMoments(const Moments& m, Eigen::Vector3f& n, float& curvature);

// gatedMoments is defined here, static, so that each source calling it gets its own vector
// clones: the dispatcher GCC emits for a target_clones function must live beside its clones.
// Its body, gatedMomentsBody, is inlined into the callers that are cloned themselves (a clone's
// call to a cloned function goes through the dispatcher).
typedef float LaneF __attribute__((vector_size(kScanLanes * sizeof(float))));

typedef float LaneQ __attribute__((vector_size(4 * sizeof(float))));
typedef std::int32_t LaneI __attribute__((vector_size(kScanLanes * sizeof(std::int32_t))));

inline void loadLanes(LaneF& v, const float* p) { std::memcpy(&v, p, sizeof v); }

// Moments, relative to p, of the points within sqrt(radius2) of p among rows [v0, v1] (every
// row_step-th) and columns [a0, a1] of the coordinate images (row stride W). Non-finite pixels
// hold kFar, so they fail the distance test like any far point; the columns read past a1 (a
// vector at a time) are real points of the cloud or kFar padding, and the ones within the
// radius are neighbours of p like any other (the window only bounds the ball).
__attribute__((always_inline)) inline Moments gatedMomentsBody(
    const float* X, const float* Y, const float* Z, std::size_t W, std::ptrdiff_t v0,
    std::ptrdiff_t v1, std::ptrdiff_t a0, std::ptrdiff_t a1, std::ptrdiff_t row_step, float px,
    float py, float pz, float radius2) {
  const LaneF zero = {};
  LaneI count = {};
  LaneF sx = zero, sy = zero, sz = zero, sxx = zero, sxy = zero, sxz = zero, syy = zero,
        syz = zero, szz = zero;
  for (std::ptrdiff_t b = v0; b <= v1; b += row_step) {
    const std::size_t row = static_cast<std::size_t>(b) * W;
    for (std::ptrdiff_t a = a0; a <= a1; a += kScanLanes) {
      const std::size_t at = row + static_cast<std::size_t>(a);
      LaneF x, y, z;
      loadLanes(x, X + at), loadLanes(y, Y + at), loadLanes(z, Z + at);
      const LaneF qx = x - px, qy = y - py, qz = z - pz;
      const LaneF d2 = qx * qx + qy * qy + qz * qz;
      // The points within the radius: all bits set in their lanes. The count as integers
      // (one subtraction instead of a mask to 1.0 and an add) and q masked to +0 outside (the
      // product with a 0 / 1 weight gave -0 for a negative q): each sum gets the same values
      // and the same zeros, which leave it as it is, so the moments are the same bit for bit.
      const LaneI in = d2 <= radius2;
      const LaneF cx = (LaneF)((LaneI)qx & in), cy = (LaneF)((LaneI)qy & in),
                  cz = (LaneF)((LaneI)qz & in);
      count -= in;
      sx += cx, sy += cy, sz += cz;
      sxx += cx * qx, sxy += cx * qy, sxz += cx * qz, syy += cy * qy, syz += cy * qz,
          szz += cz * qz;
    }
  }
  // The sum of each accumulator's lanes, (v0 + v4 + v1 + v5) + (v2 + v6 + v3 + v7) in that
  // grouping, four accumulators at a time: the halves added, then two rounds of pairwise sums
  // across accumulators (a lane-by-lane loop compiled to a scalar add per lane; one shuffle
  // per accumulator cost ~90 instructions a call).
  static_assert(kScanLanes == 8, "the reduction adds two halves of 4 lanes");
  const auto half = [](const LaneF& v) {
    LaneQ lo, hi;
    std::memcpy(&lo, &v, sizeof lo);
    std::memcpy(&hi, reinterpret_cast<const char*>(&v) + sizeof lo, sizeof hi);
    return lo + hi;  // s_l = v_l + v_(l+4)
  };
  // (a0 + a1, a2 + a3, b0 + b1, b2 + b3). GCC (12 on) and clang both have
  // __builtin_shufflevector (GCC's __builtin_shuffle is not clang's).
  const auto pairs = [](const LaneQ& a, const LaneQ& b) {
    return __builtin_shufflevector(a, b, 0, 2, 4, 6) + __builtin_shufflevector(a, b, 1, 3, 5, 7);
  };
  const auto four = [&](const LaneF& a, const LaneF& b, const LaneF& c, const LaneF& d) {
    return pairs(pairs(half(a), half(b)), pairs(half(c), half(d)));
  };
  const LaneF n = __builtin_convertvector(count, LaneF);  // exact: counts below 2^24
  const LaneQ t0 = four(n, sx, sy, sz), t1 = four(sxx, sxy, sxz, syy);
  const LaneQ t2 = pairs(pairs(half(syz), half(szz)), LaneQ{});
  Moments m;
  m.n = static_cast<double>(t0[0]), m.x = static_cast<double>(t0[1]);
  m.y = static_cast<double>(t0[2]), m.z = static_cast<double>(t0[3]);
  m.xx = static_cast<double>(t1[0]), m.xy = static_cast<double>(t1[1]);
  m.xz = static_cast<double>(t1[2]), m.yy = static_cast<double>(t1[3]);
  m.yz = static_cast<double>(t2[0]), m.zz = static_cast<double>(t2[1]);
  return m;
}

UPD_VECTOR_CLONES
[[maybe_unused]] static Moments gatedMoments(const float* X, const float* Y, const float* Z,
                                             std::size_t W, std::ptrdiff_t v0, std::ptrdiff_t v1,
                                             std::ptrdiff_t a0, std::ptrdiff_t a1,
                                             std::ptrdiff_t row_step, float px, float py,
                                             float pz, float radius2) {
  return gatedMomentsBody(X, Y, Z, W, v0, v1, a0, a1, row_step, px, py, pz, radius2);
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

}  // namespace upd::core::detail
