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

// The common path of normalFromUnitCovariance for four covariances (a .. f: the upper
// triangles' entries by lane): the unit normal (vx, vy, vz) and curvature l0 of the lanes of
// good (on entry the lanes to solve; on return those the common path settles).
struct FourNormals {
  __m256d vx, vy, vz, l0, good;
};

UPD_AVX2 FourNormals fourNormalsOf(__m256d a, __m256d b, __m256d c, __m256d d, __m256d e,
                                   __m256d f, __m256d good) {
  const __m256d one = _mm256_set1_pd(1.0), two = _mm256_set1_pd(2.0);
  const __m256d A00 = d * f - e * e, A01 = c * e - b * f, A02 = b * e - c * d;
  const __m256d A11 = a * f - c * c, A12 = b * c - a * e, A22 = a * d - b * b;
  const __m256d adj_norm2 =
      A00 * A00 + A11 * A11 + A22 * A22 + two * (A01 * A01 + A02 * A02 + A12 * A12);
  good = _mm256_and_pd(good, gt(adj_norm2, _mm256_set1_pd(1e-20)));
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
  return {vx, vy, vz, l0, good};
}

// The lanes of r into n_out, curvature_out and ok from i0 on: ok 1 where settled (the lanes of
// r.good), else `otherwise`.
UPD_AVX2 void storeFour(const FourNormals& r, std::size_t i0, Eigen::Vector3f* n_out,
                        float* curvature_out, std::uint8_t* ok, const std::uint8_t* otherwise) {
  alignas(32) double ox[4], oy[4], oz[4], ol0[4];
  _mm256_store_pd(ox, r.vx), _mm256_store_pd(oy, r.vy), _mm256_store_pd(oz, r.vz);
  _mm256_store_pd(ol0, r.l0);
  const int mask = _mm256_movemask_pd(r.good);
  for (int l = 0; l < 4; ++l) {
    const std::size_t i = i0 + static_cast<std::size_t>(l);
    if (!(mask & (1 << l))) {
      ok[i] = otherwise[l];
      continue;
    }
    n_out[i] = Eigen::Vector3f(static_cast<float>(ox[l]), static_cast<float>(oy[l]),
                               static_cast<float>(oz[l]));
    curvature_out[i] = static_cast<float>(ol0[l]);
    ok[i] = 1;
  }
}

// Four covariances from cov[i0 ...]: ok[i] = 1 and n, curvature where the common path settles
// them, else ok[i] = 2 (the caller asks the scalar function).
UPD_AVX2 void fourNormals(const double (*cov)[6], std::size_t i0, Eigen::Vector3f* n_out,
                          float* curvature_out, std::uint8_t* ok) {
  alignas(32) double e6[6][4];
  for (int l = 0; l < 4; ++l) {
    for (int k = 0; k < 6; ++k) e6[k][l] = cov[i0 + static_cast<std::size_t>(l)][k];
  }
  const FourNormals r = fourNormalsOf(
      _mm256_load_pd(e6[0]), _mm256_load_pd(e6[1]), _mm256_load_pd(e6[2]), _mm256_load_pd(e6[3]),
      _mm256_load_pd(e6[4]), _mm256_load_pd(e6[5]), _mm256_castsi256_pd(_mm256_set1_epi64x(-1)));
  const std::uint8_t scalar[4] = {2, 2, 2, 2};
  storeFour(r, i0, n_out, curvature_out, ok, scalar);
}

// Four neighbourhoods' moments from rows m (field k of neighbourhood i at m[k * stride + i]):
// unitCovariance's arithmetic lane by lane, then fourNormalsOf; ok[i] = 0 where the moments
// have no spread, 2 where the common path does not settle them.
UPD_AVX2 void fourNormalsFromMoments(const double* m, std::size_t stride, std::size_t i0,
                                     Eigen::Vector3f* n_out, float* curvature_out,
                                     std::uint8_t* ok) {
  __m256d v[10];
  for (int k = 0; k < 10; ++k) v[k] = _mm256_loadu_pd(m + static_cast<std::size_t>(k) * stride + i0);
  const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
  const __m256d inv = one / v[0];
  const __m256d mx = v[1] * inv, my = v[2] * inv, mz = v[3] * inv;
  const __m256d a = v[4] * inv - mx * mx, b = v[5] * inv - mx * my, c = v[6] * inv - mx * mz;
  const __m256d d = v[7] * inv - my * my, e = v[8] * inv - my * mz, f = v[9] * inv - mz * mz;
  const __m256d trace = a + d + f;
  const __m256d spread = _mm256_and_pd(gt(v[0], zero), gt(trace, zero));
  const __m256d s = one / trace;
  const FourNormals r = fourNormalsOf(a * s, b * s, c * s, d * s, e * s, f * s, spread);
  const int has = _mm256_movemask_pd(spread);
  const std::uint8_t otherwise[4] = {static_cast<std::uint8_t>(has & 1 ? 2 : 0),
                                     static_cast<std::uint8_t>(has & 2 ? 2 : 0),
                                     static_cast<std::uint8_t>(has & 4 ? 2 : 0),
                                     static_cast<std::uint8_t>(has & 8 ? 2 : 0)};
  storeFour(r, i0, n_out, curvature_out, ok, otherwise);
}

bool haveAvx2() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2");
}
const bool kHaveAvx2 = haveAvx2();
#endif

}  // namespace

void normalsFromMoments(const double* m, std::size_t stride, std::size_t count,
                        Eigen::Vector3f* n, float* curvature, std::uint8_t* ok) {
  const auto scalar = [&](std::size_t i) {
    Moments mi;
    double* const f[10] = {&mi.n, &mi.x, &mi.y, &mi.z, &mi.xx, &mi.xy, &mi.xz, &mi.yy, &mi.yz, &mi.zz};
    for (std::size_t k = 0; k < 10; ++k) *f[k] = m[k * stride + i];
    double cov[6];
    return unitCovariance(mi, cov) && normalFromUnitCovariance(cov, n[i], curvature[i]);
  };
  std::size_t i = 0;
#if defined(__GNUC__) && defined(__x86_64__)
  if (kHaveAvx2) {
    for (; i + 4 <= count; i += 4) fourNormalsFromMoments(m, stride, i, n, curvature, ok);
    for (std::size_t j = 0; j < i; ++j) {
      if (ok[j] == 2) ok[j] = scalar(j) ? 1 : 0;
    }
  }
#endif
  for (; i < count; ++i) ok[i] = scalar(i) ? 1 : 0;
}

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
