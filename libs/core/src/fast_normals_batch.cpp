// unitCovariance and normalFromUnitCovariance for many neighbourhoods' moments at once, four to
// an AVX2 vector of doubles or eight to an AVX-512 one (the same code for both:
// fast_normals_lanes.inc), with the scalar functions' results bit for bit: the same operations
// in the same order, each correctly rounded (this file is built with -ffp-contract=off, so that
// no multiply and add are fused), the lanes of a vector stepping together and each stopping
// where the scalar loop stops.
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

#if defined(__GNUC__) && defined(__x86_64__)
constexpr double kMaxDouble = std::numeric_limits<double>::max();

// The lanes of four doubles (AVX2): comparisons give all bits set in a lane where true.
namespace avx2 {
#define UPD_LANES __attribute__((target("avx2"))) inline
using V = __m256d;
constexpr int kN = 4;
UPD_LANES V set1(double x) { return _mm256_set1_pd(x); }
UPD_LANES V zero() { return _mm256_setzero_pd(); }
UPD_LANES V ge(V a, V b) { return _mm256_cmp_pd(a, b, _CMP_GE_OQ); }
UPD_LANES V gt(V a, V b) { return _mm256_cmp_pd(a, b, _CMP_GT_OQ); }
UPD_LANES V le(V a, V b) { return _mm256_cmp_pd(a, b, _CMP_LE_OQ); }
// m ? a : b, lane by lane.
UPD_LANES V pick(V m, V a, V b) { return _mm256_blendv_pd(b, a, m); }
// std::max(0.0, v): v where 0 < v, else 0 (NaN too).
UPD_LANES V maxZero(V v) { return _mm256_max_pd(v, _mm256_setzero_pd()); }
UPD_LANES V vsqrt(V v) { return _mm256_sqrt_pd(v); }
UPD_LANES V and_(V a, V b) { return _mm256_and_pd(a, b); }
UPD_LANES V andnot(V a, V b) { return _mm256_andnot_pd(a, b); }  // ~a & b
UPD_LANES V or_(V a, V b) { return _mm256_or_pd(a, b); }
UPD_LANES int mask(V v) { return _mm256_movemask_pd(v); }
UPD_LANES V loadu(const double* p) { return _mm256_loadu_pd(p); }
UPD_LANES void store(double* p, V v) { _mm256_store_pd(p, v); }
#include "fast_normals_lanes.inc"
#undef UPD_LANES
}  // namespace avx2

// The lanes of eight doubles (AVX-512), a lane's truth as all its bits set too (converted from
// and to the mask registers), so that the same code serves both widths. (GCC 12.2 warns that
// the unmasked AVX-512 intrinsics read an uninitialized value: their pass-through operand is
// _mm512_undefined_pd() by design; a false positive.)
#pragma GCC diagnostic push
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
namespace avx512 {
#define UPD_LANES __attribute__((target("avx512f,avx512dq"))) inline
using V = __m512d;
constexpr int kN = 8;
UPD_LANES V set1(double x) { return _mm512_set1_pd(x); }
UPD_LANES V zero() { return _mm512_setzero_pd(); }
UPD_LANES V lanes(__mmask8 m) { return _mm512_castsi512_pd(_mm512_movm_epi64(m)); }
UPD_LANES V ge(V a, V b) { return lanes(_mm512_cmp_pd_mask(a, b, _CMP_GE_OQ)); }
UPD_LANES V gt(V a, V b) { return lanes(_mm512_cmp_pd_mask(a, b, _CMP_GT_OQ)); }
UPD_LANES V le(V a, V b) { return lanes(_mm512_cmp_pd_mask(a, b, _CMP_LE_OQ)); }
UPD_LANES int mask(V v) { return _mm512_movepi64_mask(_mm512_castpd_si512(v)); }
UPD_LANES V pick(V m, V a, V b) {
  return _mm512_mask_blend_pd(static_cast<__mmask8>(mask(m)), b, a);
}
UPD_LANES V maxZero(V v) { return _mm512_max_pd(v, _mm512_setzero_pd()); }
UPD_LANES V vsqrt(V v) { return _mm512_sqrt_pd(v); }
UPD_LANES V and_(V a, V b) { return _mm512_and_pd(a, b); }
UPD_LANES V andnot(V a, V b) { return _mm512_andnot_pd(a, b); }  // ~a & b
UPD_LANES V or_(V a, V b) { return _mm512_or_pd(a, b); }
UPD_LANES V loadu(const double* p) { return _mm512_loadu_pd(p); }
UPD_LANES void store(double* p, V v) { _mm512_store_pd(p, v); }
#include "fast_normals_lanes.inc"
#undef UPD_LANES
}  // namespace avx512
#pragma GCC diagnostic pop

const bool kHaveAvx2 = cpuHasAvx2();
const bool kHaveAvx512 = kHaveAvx2 && cpuHasAvx512();
#else
constexpr bool kHaveAvx2 = false, kHaveAvx512 = false;
#endif

// Moments' row i, solved by the scalar functions: ok[i] and n[i], curvature[i].
void scalarFromMoments(const double* m, std::size_t stride, std::size_t i, Eigen::Vector3f* n,
                       float* curvature, std::uint8_t* ok) {
  Moments mi;
  double* const f[10] = {&mi.n, &mi.x, &mi.y, &mi.z, &mi.xx, &mi.xy, &mi.xz, &mi.yy, &mi.yz, &mi.zz};
  for (std::size_t k = 0; k < 10; ++k) *f[k] = m[k * stride + i];
  double cov[6];
  ok[i] = unitCovariance(mi, cov) && normalFromUnitCovariance(cov, n[i], curvature[i]) ? 1 : 0;
}

void fromMoments(const double* m, std::size_t stride, std::size_t count, Eigen::Vector3f* n,
                 float* curvature, std::uint8_t* ok, bool wide) {
  std::size_t i = 0;
#if defined(__GNUC__) && defined(__x86_64__)
  if (kHaveAvx512 && wide) {
    for (; i + 8 <= count; i += 8) avx512::normalsOfMoments(m, stride, i, n, curvature, ok);
  }
  if (kHaveAvx2) {
    for (; i + 4 <= count; i += 4) avx2::normalsOfMoments(m, stride, i, n, curvature, ok);
  }
  for (std::size_t j = 0; j < i; ++j) {
    if (ok[j] == 2) scalarFromMoments(m, stride, j, n, curvature, ok);
  }
#endif
  for (; i < count; ++i) scalarFromMoments(m, stride, i, n, curvature, ok);
}

}  // namespace

void normalsFromMoments(const double* m, std::size_t stride, std::size_t count,
                        Eigen::Vector3f* n, float* curvature, std::uint8_t* ok) {
  fromMoments(m, stride, count, n, curvature, ok, true);
}

void normalsFromMomentsWithoutAvx512(const double* m, std::size_t stride, std::size_t count,
                                     Eigen::Vector3f* n, float* curvature, std::uint8_t* ok) {
  fromMoments(m, stride, count, n, curvature, ok, false);
}

}  // namespace upd::core::detail
