// The outlier filter's inner steps on AVX-512 (the versions for other CPUs are in
// preprocess_outlier_kernels.cpp): the gathering of the candidates within a bound, 16 at a time
// packed by a compress, and the selection of the k nearest by sorting networks: up to 32
// candidates sorted in two vectors of 16 (bitonic networks, a permutation, a minimum, a maximum
// and a blend a step), no branch and no chain of dependent maxima. The mean of the square roots
// of the want smallest and the want-th are selectMean's (the roots in float, summed in double).
// (GCC 12.2 warns that the unmasked AVX-512 intrinsics read an uninitialized value: their
// pass-through operand is _mm512_undefined_ps() by design; a false positive.)
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include "preprocess_internal.h"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <limits>

namespace upd::core::detail {

namespace {

// The lanes that keep the larger at step (k, j) of a bitonic network, in a block of k lanes
// sorted ascending where (i & k) = 0 and descending elsewhere: (i & j) != 0 xor (i & k) != 0.
constexpr __mmask16 takeMax(int k, int j) {
  unsigned mask = 0;
  for (int i = 0; i < 16; ++i) {
    if (((i & j) != 0) != ((i & k) != 0)) mask |= 1u << i;
  }
  return static_cast<__mmask16>(mask);
}

// v with lane i moved to lane i ^ J: within 128 bits by an immediate shuffle for J = 1 and 2,
// whole 128-bit blocks swapped for J = 4 and 8 (no permutation table to load).
template <int J>
__attribute__((target("avx512f"))) inline __m512 partners(__m512 v) {
  if constexpr (J == 1) return _mm512_permute_ps(v, 0xB1);
  if constexpr (J == 2) return _mm512_permute_ps(v, 0x4E);
  if constexpr (J == 4) return _mm512_shuffle_f32x4(v, v, 0xB1);
  return _mm512_shuffle_f32x4(v, v, 0x4E);  // J == 8
}

// One compare-exchange step (K, J) of a bitonic network on a and b (two independent chains):
// lane i against lane i ^ J, the lanes of takeMax(K, J) keeping the larger.
template <int K, int J>
__attribute__((target("avx512f"))) inline void exchange(__m512& a, __m512& b) {
  const __m512 pa = partners<J>(a), pb = partners<J>(b);
  constexpr __mmask16 m = takeMax(K, J);
  a = _mm512_mask_blend_ps(m, _mm512_min_ps(a, pa), _mm512_max_ps(a, pa));
  b = _mm512_mask_blend_ps(m, _mm512_min_ps(b, pb), _mm512_max_ps(b, pb));
}

// Step (K, J) on each pair of the vectors v[0, N).
template <int K, int J, int N>
__attribute__((target("avx512f"))) inline void step(__m512 (&v)[N]) {
  static_assert(N % 2 == 0, "the vectors go in pairs");
  for (int i = 0; i < N; i += 2) exchange<K, J>(v[i], v[i + 1]);
}

// Each of the vectors v[0, N) sorted ascending: steps k = 2, 4, 8, 16 and j = k / 2 .. 1, the
// vectors in pairs (independent chains, interleaved step by step).
template <int N>
__attribute__((target("avx512f"))) inline void sortEach(__m512 (&v)[N]) {
  step<2, 1>(v);
  step<4, 2>(v), step<4, 1>(v);
  step<8, 4>(v), step<8, 2>(v), step<8, 1>(v);
  step<16, 8>(v), step<16, 4>(v), step<16, 2>(v), step<16, 1>(v);
}

// Bitonic sequences a and b into ascending order: the last four steps.
__attribute__((target("avx512f"))) inline void mergeTwo(__m512& a, __m512& b) {
  exchange<16, 8>(a, b), exchange<16, 4>(a, b), exchange<16, 2>(a, b), exchange<16, 1>(a, b);
}

// The sum of the square roots of the lanes of v in keep, in double: the roots in float, the
// two halves widened and added, then the 8 lanes by the tree of _mm512_reduce_add_pd.
__attribute__((target("avx512f"))) inline double sumRoots(__m512 v, __mmask16 keep) {
  const __m512 r = _mm512_maskz_sqrt_ps(keep, v);
  const __m512d lo = _mm512_cvtps_pd(_mm512_castps512_ps256(r));
  const __m512d hi = _mm512_cvtps_pd(_mm256_castpd_ps(_mm512_extractf64x4_pd(_mm512_castps_pd(r), 1)));
  return _mm512_reduce_add_pd(_mm512_add_pd(lo, hi));
}

// The lanes [0, n) of 16 (n <= 16: a mask; more: all).
inline __mmask16 lanes(std::size_t n) {
  return static_cast<__mmask16>(n >= 16 ? 0xFFFFu : (1u << n) - 1u);
}

// cand[0, c), c <= 32, into a and b, the lanes past c +inf (sorted to the end, never kept).
__attribute__((target("avx512f"))) inline void load(const float* cand, std::size_t c, __m512& a,
                                                    __m512& b) {
  const __m512 inf = _mm512_set1_ps(std::numeric_limits<float>::infinity());
  a = _mm512_mask_loadu_ps(inf, lanes(c), cand);
  b = c > 16 ? _mm512_mask_loadu_ps(inf, lanes(c - 16), cand + 16) : inf;
}

// The mean of the square roots of the want smallest of a and b (each sorted ascending), and
// the want-th into kth.
__attribute__((target("avx512f"))) inline double meanOfSorted(__m512 a, __m512 b, std::size_t want,
                                                              float& kth) {
  // The 16 smallest of both and the 16 largest, each a bitonic sequence: a against b reversed.
  const __m512i reverse = _mm512_setr_epi32(15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0);
  const __m512 rb = _mm512_permutexvar_ps(reverse, b);
  __m512 low = _mm512_min_ps(a, rb), high = _mm512_max_ps(a, rb);
  double sum;
  if (want == 17) {  // (the default k = 16: all 16 smallest, and the least of the rest)
    kth = _mm512_reduce_min_ps(high);
    sum = sumRoots(low, 0xFFFF) + static_cast<double>(std::sqrt(kth));
  } else {
    mergeTwo(low, high);  // (the 32 in order: low, then high)
    alignas(64) float s[32];
    _mm512_store_ps(s, low), _mm512_store_ps(s + 16, high);
    kth = s[want - 1];
    sum = want <= 16 ? sumRoots(low, lanes(want))
                     : sumRoots(low, 0xFFFF) + sumRoots(high, lanes(want - 16));
  }
  return sum / static_cast<double>(want - 1);
}

}  // namespace

__attribute__((target("avx512f,fma,popcnt"))) std::size_t gatherWithinAvx512(
    const float* __restrict x, const float* __restrict y, const float* __restrict z,
    std::size_t n, float qx, float qy, float qz, float t, float* __restrict cand) {
  const __m512 vx = _mm512_set1_ps(qx), vy = _mm512_set1_ps(qy), vz = _mm512_set1_ps(qz);
  const __m512 vt = _mm512_set1_ps(t);
  std::size_t c = 0, j = 0;
  // (The lanes of gatherWithinAvx2, the same arithmetic: the same distances bit for bit.)
  for (; j + 16 <= n; j += 16) {
    const __m512 dx = _mm512_sub_ps(_mm512_loadu_ps(x + j), vx);
    const __m512 dy = _mm512_sub_ps(_mm512_loadu_ps(y + j), vy);
    const __m512 dz = _mm512_sub_ps(_mm512_loadu_ps(z + j), vz);
    const __m512 d2 = _mm512_fmadd_ps(dz, dz, _mm512_fmadd_ps(dy, dy, _mm512_mul_ps(dx, dx)));
    const __mmask16 within = _mm512_cmp_ps_mask(d2, vt, _CMP_LE_OQ);
    _mm512_storeu_ps(cand + c, _mm512_maskz_compress_ps(within, d2));
    c += static_cast<std::size_t>(__builtin_popcount(within));
  }
  if (j < n) {  // (n is a multiple of 8: the last 8)
    const __mmask16 eight = 0xFF;
    const __m512 dx = _mm512_sub_ps(_mm512_maskz_loadu_ps(eight, x + j), vx);
    const __m512 dy = _mm512_sub_ps(_mm512_maskz_loadu_ps(eight, y + j), vy);
    const __m512 dz = _mm512_sub_ps(_mm512_maskz_loadu_ps(eight, z + j), vz);
    const __m512 d2 = _mm512_fmadd_ps(dz, dz, _mm512_fmadd_ps(dy, dy, _mm512_mul_ps(dx, dx)));
    const __mmask16 within = _mm512_mask_cmp_ps_mask(eight, d2, vt, _CMP_LE_OQ);
    _mm512_mask_storeu_ps(cand + c, eight, _mm512_maskz_compress_ps(within, d2));
    c += static_cast<std::size_t>(__builtin_popcount(within));
  }
  return c;
}

__attribute__((target("avx512f"))) double selectMeanSorted(const float* cand, std::size_t c,
                                                           std::size_t want, float& kth) {
  __m512 v[2];
  load(cand, c, v[0], v[1]);
  sortEach(v);
  return meanOfSorted(v[0], v[1], want, kth);
}

__attribute__((target("avx512f"))) void selectMeansSorted(const float* cand0, std::size_t c0,
                                                          const float* cand1, std::size_t c1,
                                                          std::size_t want, float& kth0,
                                                          float& kth1, double& mean0,
                                                          double& mean1) {
  __m512 v[4];
  load(cand0, c0, v[0], v[1]);
  load(cand1, c1, v[2], v[3]);
  sortEach(v);
  mean0 = meanOfSorted(v[0], v[1], want, kth0);
  mean1 = meanOfSorted(v[2], v[3], want, kth1);
}

}  // namespace upd::core::detail

#else
#include <vector>

namespace upd::core::detail {

// (Without AVX-512: selectsSorted is false, and these are not called; defined for the link,
// by the versions this build has.)
std::size_t gatherWithinAvx512(const float* x, const float* y, const float* z, std::size_t n,
                               float qx, float qy, float qz, float t, float* cand) {
  return gatherWithin(x, y, z, n, qx, qy, qz, t, cand);
}

double selectMeanSorted(const float* cand, std::size_t c, std::size_t want, float& kth) {
  std::vector<float> copy(cand, cand + c);
  return selectMean(copy.data(), c, want, kth);
}

void selectMeansSorted(const float* cand0, std::size_t c0, const float* cand1, std::size_t c1,
                       std::size_t want, float& kth0, float& kth1, double& mean0,
                       double& mean1) {
  mean0 = selectMeanSorted(cand0, c0, want, kth0);
  mean1 = selectMeanSorted(cand1, c1, want, kth1);
}

}  // namespace upd::core::detail

#endif
