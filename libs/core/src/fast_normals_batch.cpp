// normalFromUnitCovariance for many covariances at once, four to an AVX2 vector of doubles, with
// the scalar function's results bit for bit: the same operations in the same order, each
// correctly rounded (this file is built with -ffp-contract=off, so that no multiply and add are
// fused), the lanes of a vector stepping together and each stopping where the scalar loop stops.
// A lane the common path does not settle (no clear plane: the general eigen solver; a
// degenerate covariance; a step of zero length) is handed to the scalar function.
#include <cmath>
#include <cstdint>
#include <limits>

#include "fast_normals_internal.h"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

namespace upd::core::detail {

namespace {

void scalarNormals(const double (*cov)[6], std::size_t begin, std::size_t end,
                   Eigen::Vector3f* n, float* curvature, std::uint8_t* ok) {
  for (std::size_t i = begin; i < end; ++i) {
    ok[i] = normalFromUnitCovariance(cov[i], n[i], curvature[i]) ? 1 : 0;
  }
}

#if defined(__GNUC__) && defined(__x86_64__)
// (Intrinsics for the comparisons, the selects and the square root; the arithmetic by GCC's
// operators on __m256d, evaluated in the order written, as the scalar code's.)
#define UPD_AVX2 __attribute__((target("avx2")))

constexpr double kMaxDouble = std::numeric_limits<double>::max();

UPD_AVX2 inline __m256d ge(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_GE_OQ); }
UPD_AVX2 inline __m256d gt(__m256d a, __m256d b) { return _mm256_cmp_pd(a, b, _CMP_GT_OQ); }
// m ? a : b, lane by lane.
UPD_AVX2 inline __m256d pick(__m256d m, __m256d a, __m256d b) { return _mm256_blendv_pd(b, a, m); }
// std::max(0.0, v): v where 0 < v, else 0 (NaN too).
UPD_AVX2 inline __m256d maxZero(__m256d v) { return _mm256_max_pd(v, _mm256_setzero_pd()); }

// The scalar function's last loop for the lanes of active: products with B until a step moves
// v by less than 1e-5 rad (at most 20); returns the lanes where a product vanished (the scalar
// function stops there without a step: they go to it).
UPD_AVX2 __m256d settle(__m256d B00, __m256d B01, __m256d B02, __m256d B11, __m256d B12,
                        __m256d B22, __m256d active, __m256d& vx, __m256d& vy, __m256d& vz) {
  const __m256d one = _mm256_set1_pd(1.0), settled = _mm256_set1_pd(1.0 - 5e-11);
  __m256d fail = _mm256_setzero_pd();
  for (int it = 0; it < 20 && _mm256_movemask_pd(active) != 0; ++it) {
    const __m256d wx = B00 * vx + B01 * vy + B02 * vz;
    const __m256d wy = B01 * vx + B11 * vy + B12 * vz;
    const __m256d wz = B02 * vx + B12 * vy + B22 * vz;
    const __m256d norm2 = wx * wx + wy * wy + wz * wz;
    const __m256d stop = _mm256_andnot_pd(gt(norm2, _mm256_setzero_pd()), active);
    fail = _mm256_or_pd(fail, stop);
    active = _mm256_andnot_pd(stop, active);
    const __m256d k = one / _mm256_sqrt_pd(norm2);
    const __m256d cos_step = (wx * vx + wy * vy + wz * vz) * k;
    vx = pick(active, wx * k, vx), vy = pick(active, wy * k, vy), vz = pick(active, wz * k, vz);
    active = _mm256_andnot_pd(gt(cos_step, settled), active);
  }
  return fail;
}

// Four covariances from cov[i0 ...]: ok[i] = 1 and n, curvature where the common path settles
// them, else ok[i] = 2 (the caller asks the scalar function).
UPD_AVX2 void fourNormals(const double (*cov)[6], std::size_t i0, Eigen::Vector3f* n_out,
                          float* curvature_out, std::uint8_t* ok) {
  alignas(32) double e6[6][4];
  for (int l = 0; l < 4; ++l) {
    for (int k = 0; k < 6; ++k) e6[k][l] = cov[i0 + static_cast<std::size_t>(l)][k];
  }
  const __m256d a = _mm256_load_pd(e6[0]), b = _mm256_load_pd(e6[1]), c = _mm256_load_pd(e6[2]),
                d = _mm256_load_pd(e6[3]), e = _mm256_load_pd(e6[4]), f = _mm256_load_pd(e6[5]);
  const __m256d one = _mm256_set1_pd(1.0), two = _mm256_set1_pd(2.0);
  const __m256d A00 = d * f - e * e, A01 = c * e - b * f, A02 = b * e - c * d;
  const __m256d A11 = a * f - c * c, A12 = b * c - a * e, A22 = a * d - b * b;
  const __m256d adj_norm2 =
      A00 * A00 + A11 * A11 + A22 * A22 + two * (A01 * A01 + A02 * A02 + A12 * A12);
  __m256d good = gt(adj_norm2, _mm256_set1_pd(1e-20));
  const __m256d B00 = A00 * A00 + A01 * A01 + A02 * A02;
  const __m256d B01 = A00 * A01 + A01 * A11 + A02 * A12;
  const __m256d B02 = A00 * A02 + A01 * A12 + A02 * A22;
  const __m256d B11 = A01 * A01 + A11 * A11 + A12 * A12;
  const __m256d B12 = A01 * A02 + A11 * A12 + A12 * A22;
  const __m256d B22 = A02 * A02 + A12 * A12 + A22 * A22;
  const __m256d col0 = _mm256_and_pd(ge(B00, B11), ge(B00, B22)), col1 = ge(B11, B22);
  __m256d vx = pick(col0, B00, pick(col1, B01, B02));
  __m256d vy = pick(col0, B01, pick(col1, B11, B12));
  __m256d vz = pick(col0, B02, pick(col1, B12, B22));
  for (int it = 0; it < 3; ++it) {
    const __m256d wx = B00 * vx + B01 * vy + B02 * vz;
    const __m256d wy = B01 * vx + B11 * vy + B12 * vz;
    const __m256d wz = B02 * vx + B12 * vy + B22 * vz;
    vx = wx, vy = wy, vz = wz;
  }
  const __m256d norm2 = vx * vx + vy * vy + vz * vz;
  // (norm2 > 0 and finite: below the largest double, which NaN fails too.)
  good = _mm256_and_pd(good, _mm256_and_pd(gt(norm2, _mm256_setzero_pd()),
                                           _mm256_cmp_pd(norm2, _mm256_set1_pd(kMaxDouble),
                                                         _CMP_LE_OQ)));
  const __m256d k = one / _mm256_sqrt_pd(norm2);
  vx = vx * k, vy = vy * k, vz = vz * k;
  const __m256d q0 = vx * (a * vx + b * vy + c * vz) + vy * (b * vx + d * vy + e * vz) +
                     vz * (c * vx + e * vy + f * vz);
  const __m256d det = a * A00 + b * A01 + c * A02;
  const __m256d rest = one - q0;
  const __m256d l1 =
      pick(gt(q0, _mm256_set1_pd(1e-12)),
           _mm256_set1_pd(0.5) *
               (rest - _mm256_sqrt_pd(maxZero(rest * rest - _mm256_set1_pd(4.0) * det / q0))),
           rest);
  // (l1 < 2 q0: the general solver's lane. !(l1 < 2 q0) keeps NaN out as the scalar branch does
  // not: a NaN l1 goes on to the loop there; here it goes to the scalar function, the same.)
  good = _mm256_and_pd(good, ge(l1, two * q0));
  good = _mm256_andnot_pd(settle(B00, B01, B02, B11, B12, B22, good, vx, vy, vz), good);
  const __m256d l0 = maxZero(vx * (a * vx + b * vy + c * vz) + vy * (b * vx + d * vy + e * vz) +
                             vz * (c * vx + e * vy + f * vz));
  alignas(32) double ox[4], oy[4], oz[4], ol0[4];
  _mm256_store_pd(ox, vx), _mm256_store_pd(oy, vy), _mm256_store_pd(oz, vz);
  _mm256_store_pd(ol0, l0);
  const int mask = _mm256_movemask_pd(good);
  for (int l = 0; l < 4; ++l) {
    const std::size_t i = i0 + static_cast<std::size_t>(l);
    if (!(mask & (1 << l))) {
      ok[i] = 2;
      continue;
    }
    n_out[i] = Eigen::Vector3f(static_cast<float>(ox[l]), static_cast<float>(oy[l]),
                               static_cast<float>(oz[l]));
    curvature_out[i] = static_cast<float>(ol0[l]);
    ok[i] = 1;
  }
}

bool haveAvx2() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");
}
const bool kHaveAvx2 = haveAvx2();
#endif

}  // namespace

void normalsFromUnitCovariances(const double (*cov)[6], std::size_t count, Eigen::Vector3f* n,
                                float* curvature, std::uint8_t* ok) {
  std::size_t i = 0;
#if defined(__GNUC__) && defined(__x86_64__)
  if (kHaveAvx2) {
    for (; i + 4 <= count; i += 4) fourNormals(cov, i, n, curvature, ok);
    for (std::size_t j = 0; j < i; ++j) {
      if (ok[j] == 2) ok[j] = normalFromUnitCovariance(cov[j], n[j], curvature[j]) ? 1 : 0;
    }
  }
#endif
  scalarNormals(cov, i, count, n, curvature, ok);
}

}  // namespace upd::core::detail
