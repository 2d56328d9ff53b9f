// The outlier filter's inner steps, gatherWithin, selectMean and the cells of its grid
// (cellCoords, preprocess_internal.h), in a version for AVX2 by intrinsics and a plain one, the
// one for the running CPU chosen once when the library loads.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "fast_cell_map.h"
#include "fast_simd.h"
#include "preprocess_internal.h"
#include "upd/core/openmp.h"
#include "upd/core/vector_clones.h"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

namespace upd::core::detail {

namespace {

std::size_t gatherWithinScalar(const float* __restrict x, const float* __restrict y,
                               const float* __restrict z, std::size_t n, float qx, float qy,
                               float qz, float t, float* __restrict cand) {
  std::size_t c = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const float dx = x[j] - qx, dy = y[j] - qy, dz = z[j] - qz;
    const float d2 = dx * dx + dy * dy + dz * dz;
    cand[c] = d2;
    c += d2 <= t ? 1 : 0;
  }
  return c;
}

#if defined(__GNUC__) && defined(__x86_64__)
// For each 8-bit mask, the lanes whose bit is set, in order, one byte each (AVX2 has no
// compress: a permutation by these indices packs the lanes).
constexpr std::array<std::uint64_t, 256> kCompressIndex = [] {
  std::array<std::uint64_t, 256> t{};
  for (std::uint32_t m = 0; m < 256; ++m) {
    std::uint64_t v = 0;
    int k = 0;
    for (std::uint32_t lane = 0; lane < 8; ++lane) {
      if (m & (1u << lane)) v |= static_cast<std::uint64_t>(lane) << (8 * k++);
    }
    t[m] = v;
  }
  return t;
}();

__attribute__((target("avx2,fma,popcnt"))) std::size_t gatherWithinAvx2(
    const float* __restrict x, const float* __restrict y, const float* __restrict z,
    std::size_t n, float qx, float qy, float qz, float t, float* __restrict cand) {
  const __m256 vx = _mm256_set1_ps(qx), vy = _mm256_set1_ps(qy), vz = _mm256_set1_ps(qz);
  const __m256 vt = _mm256_set1_ps(t);
  std::size_t c = 0;
  for (std::size_t j = 0; j < n; j += 8) {
    const __m256 dx = _mm256_sub_ps(_mm256_loadu_ps(x + j), vx);
    const __m256 dy = _mm256_sub_ps(_mm256_loadu_ps(y + j), vy);
    const __m256 dz = _mm256_sub_ps(_mm256_loadu_ps(z + j), vz);
    const __m256 d2 = _mm256_fmadd_ps(dz, dz, _mm256_fmadd_ps(dy, dy, _mm256_mul_ps(dx, dx)));
    const auto mt = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(d2, vt, _CMP_LE_OQ)));
    const __m256i idx = _mm256_cvtepu8_epi32(
        _mm_cvtsi64_si128(static_cast<long long>(kCompressIndex[mt])));
    _mm256_storeu_ps(cand + c, _mm256_permutevar8x32_ps(d2, idx));
    c += static_cast<std::size_t>(__builtin_popcount(mt));
  }
  return c;
}
#endif

const GatherWithinFn pickedGatherWithin = gatherWithinVersions().front().fn;

// By a partial selection of the want smallest.
double selectMeanScalar(float* cand, std::size_t c, std::size_t want, float& kth) {
  if (c > want) std::nth_element(cand, cand + (want - 1), cand + c);
  // (The nearest, the point itself at 0, adds nothing to the sum.)
  double s = 0;
  float top = 0.f;
  for (std::size_t j = 0; j < want; ++j) {
    s += std::sqrt(static_cast<double>(cand[j]));
    top = std::max(top, cand[j]);
  }
  kth = top;
  return s / static_cast<double>(want - 1);
}

#if defined(__GNUC__) && defined(__x86_64__)
// The horizontal maximum of v in every lane.
__attribute__((target("avx2"))) inline __m256 maxAllLanes(__m256 v) {
  v = _mm256_max_ps(v, _mm256_permute2f128_ps(v, v, 1));
  v = _mm256_max_ps(v, _mm256_shuffle_ps(v, v, 0x4e));
  return _mm256_max_ps(v, _mm256_shuffle_ps(v, v, 0xb1));
}

// The candidates of cand[0, c) within the smallest of a few bounds around guess (squared,
// spaced by a factor 1.6) that keeps at least want of them, packed to the front in order;
// returns their number (c when no bound keeps want, or guess is not a positive number). Every
// bound that keeps want keeps the want smallest, so the selection among the rest is the same.
// cand has room for c rounded up to a multiple of 8.
__attribute__((target("avx2,popcnt"))) std::size_t narrowAvx2(float* cand, std::size_t c,
                                                              std::size_t want, float guess) {
  constexpr int kBounds = 6;
  constexpr float kFactor[kBounds] = {0.4f, 0.64f, 1.f, 1.6f, 2.56f, 4.1f};
  if (!(guess > 0.f) || !(guess < std::numeric_limits<float>::max() / 8)) return c;
  const std::size_t nv = (c + 7) / 8;
  for (std::size_t j = c; j < nv * 8; ++j) cand[j] = std::numeric_limits<float>::infinity();
  __m256 bound[kBounds];
  for (int b = 0; b < kBounds; ++b) bound[b] = _mm256_set1_ps(guess * kFactor[b]);
  std::size_t count[kBounds] = {};
  for (std::size_t i = 0; i < nv; ++i) {
    const __m256 d = _mm256_loadu_ps(cand + 8 * i);
    for (int b = 0; b < kBounds; ++b) {
      count[b] += static_cast<std::size_t>(__builtin_popcount(static_cast<unsigned>(
          _mm256_movemask_ps(_mm256_cmp_ps(d, bound[b], _CMP_LE_OQ)))));
    }
  }
  int pick = 0;
  while (pick < kBounds && count[pick] < want) ++pick;
  if (pick == kBounds || count[pick] == c) return c;
  std::size_t kept = 0;  // (in place: a vector is stored at or before where it was read)
  for (std::size_t i = 0; i < nv; ++i) {
    const __m256 d = _mm256_loadu_ps(cand + 8 * i);
    const auto m = static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(d, bound[pick], _CMP_LE_OQ)));
    const __m256i idx = _mm256_cvtepu8_epi32(
        _mm_cvtsi64_si128(static_cast<long long>(kCompressIndex[m])));
    _mm256_storeu_ps(cand + kept, _mm256_permutevar8x32_ps(d, idx));
    kept += static_cast<std::size_t>(__builtin_popcount(m));
  }
  return kept;
}

// The square roots of the lanes of v[0, NV) summed in double, 4 lanes at a time (the lanes at
// -inf, dropped or padding, add 0), and the 4 sums added in pairs. (The roots in float, 8 at a
// time: their rounding, 2^-24 of the distance, is that of the float squared distances they are
// taken of.)
template <std::size_t NV>
__attribute__((target("avx2"))) inline double sumRoots(const __m256 (&v)[NV]) {
  const __m256 zero = _mm256_setzero_ps();
  __m256d sum = _mm256_setzero_pd();
  for (std::size_t i = 0; i < NV; ++i) {
    const __m256 r = _mm256_sqrt_ps(_mm256_max_ps(v[i], zero));
    sum = _mm256_add_pd(sum, _mm256_cvtps_pd(_mm256_castps256_ps128(r)));
    sum = _mm256_add_pd(sum, _mm256_cvtps_pd(_mm256_extractf128_ps(r, 1)));
  }
  // ((l0 + l1) + (l2 + l3), in registers: no aligned stack array, no realigned frame.)
  const __m128d pairs =
      _mm_hadd_pd(_mm256_castpd256_pd128(sum), _mm256_extractf128_pd(sum, 1));
  return _mm_cvtsd_f64(_mm_add_sd(pairs, _mm_unpackhi_pd(pairs, pairs)));
}

// The largest lane of v[0, NV), in every lane.
template <std::size_t NV>
__attribute__((target("avx2"))) inline __m256 maxOf(const __m256 (&v)[NV]) {
  __m256 m = v[0];
  for (std::size_t i = 1; i < NV; ++i) m = _mm256_max_ps(m, v[i]);
  return maxAllLanes(m);
}

// cand[0, c) into v[0, NV), 8 (NV - 1) < c <= 8 NV, the lanes past c -inf.
template <std::size_t NV>
__attribute__((target("avx2"))) inline void loadPadded(const float* cand, std::size_t c,
                                                       __m256 (&v)[NV]) {
  for (std::size_t i = 0; i < NV; ++i) v[i] = _mm256_loadu_ps(cand + 8 * i);
  const __m256i in_last =
      _mm256_cmpgt_epi32(_mm256_set1_epi32(static_cast<int>(c - 8 * (NV - 1))),
                         _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
  v[NV - 1] = _mm256_blendv_ps(_mm256_set1_ps(-std::numeric_limits<float>::infinity()),
                               v[NV - 1], _mm256_castsi256_ps(in_last));
}

// selectMeanAvx2's drops and sum over NV vectors (a count known when compiled, so that the
// vectors stay in registers): cand[0, c) with 8 (NV - 1) < c <= 8 NV, the lanes past c -inf.
// Those beyond a bound near the incoming kth that keeps want go first, all at once; then the
// largest go by value, every lane equal to the largest at once (a compare and a blend per
// vector, no search for its lane); where that left fewer than want (a value among those
// dropped twice, or the want-th's among them), they go again one instance at a time from the
// start. Either way the lanes kept are the same, in the same places, so the sum is the same
// bit for bit.
// (Not inlined into selectMeanAvx2: the larger counts' spills would give every call their
// realigned stack frame.)
template <std::size_t NV>
__attribute__((target("avx2,popcnt,bmi"), noinline)) double dropAndSum(const float* cand,
                                                                       std::size_t c,
                                                                       std::size_t want,
                                                                       float& kth) {
  const __m256i lane_index = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256 lowest_v = _mm256_set1_ps(-std::numeric_limits<float>::infinity());
  __m256 v[NV];
  loadPadded(cand, c, v);
  std::size_t drops = c - want;
  if (drops > 2) {
    // Those beyond the tightest of a few bounds near the incoming kth (the previous point's)
    // that keeps want go at once: they are larger than the want-th. (The counts against every
    // bound are independent compares; each drop left after them is a chain of dependent ones.)
    constexpr int kBounds = 6;
    constexpr float kFactor[kBounds] = {0.86f, 0.91f, 0.96f, 1.01f, 1.07f, 1.14f};
    __m256 bound[kBounds];
    std::size_t within[kBounds] = {};
    for (int b = 0; b < kBounds; ++b) bound[b] = _mm256_set1_ps(kth * kFactor[b]);
    for (std::size_t i = 0; i < NV; ++i) {
      for (int b = 0; b < kBounds; ++b) {
        within[b] += static_cast<std::size_t>(__builtin_popcount(static_cast<unsigned>(
            _mm256_movemask_ps(_mm256_cmp_ps(v[i], bound[b], _CMP_LE_OQ)))));
      }
    }
    const std::size_t pad = 8 * NV - c;  // (the padding, -inf, lies within any bound)
    int b = 0;
    while (b < kBounds && within[b] < want + pad) ++b;
    if (b < kBounds) {
      for (std::size_t i = 0; i < NV; ++i) {
        v[i] = _mm256_blendv_ps(lowest_v, v[i], _mm256_cmp_ps(v[i], bound[b], _CMP_LE_OQ));
      }
      drops = within[b] - pad - want;
    }
  }
  for (std::size_t drop = 0; drop < drops; ++drop) {
    const __m256 top = maxOf(v);
    for (std::size_t i = 0; i < NV; ++i) {
      v[i] = _mm256_blendv_ps(v[i], lowest_v, _mm256_cmp_ps(v[i], top, _CMP_EQ_OQ));
    }
  }
  std::size_t left = 0;
  for (std::size_t i = 0; i < NV; ++i) {
    left += static_cast<std::size_t>(__builtin_popcount(static_cast<unsigned>(
        _mm256_movemask_ps(_mm256_cmp_ps(v[i], lowest_v, _CMP_NEQ_OQ)))));
  }
  if (left != want) {
    loadPadded(cand, c, v);
    for (std::size_t drop = 0; drop < c - want; ++drop) {
      const __m256 top = maxOf(v);
      // One instance of the largest goes (ties: the others stay, as in a selection).
      for (std::size_t i = 0; i < NV; ++i) {
        const auto eq =
            static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(v[i], top, _CMP_EQ_OQ)));
        if (eq == 0) continue;
        const __m256i lane = _mm256_set1_epi32(static_cast<int>(__builtin_ctz(eq)));
        v[i] = _mm256_blendv_ps(v[i], lowest_v,
                                _mm256_castsi256_ps(_mm256_cmpeq_epi32(lane_index, lane)));
        break;
      }
    }
  }
  kth = _mm_cvtss_f32(_mm256_castps256_ps128(maxOf(v)));  // (the want-th, the largest left)
  return sumRoots(v) / static_cast<double>(want - 1);
}

// By dropping the c - want largest (the candidates within the previous point's bound exceed
// want by a few): each drop a maximum over a few vectors, no branch per candidate;
// then the square roots of the rest summed a vector at a time. Many candidates (the first
// point of a thread, a point gathered within its block's margin): first narrowed to those
// within a bound near the incoming kth (the previous point's), then, if still many, the
// partial selection.
__attribute__((target("avx2,popcnt,bmi"))) double selectMeanAvx2(float* cand, std::size_t c,
                                                                 std::size_t want, float& kth) {
  if (c - want > 16) c = narrowAvx2(cand, c, want, kth);
  if (c - want > 16) return selectMeanScalar(cand, c, want, kth);
  switch ((c + 7) / 8) {
    case 1: return dropAndSum<1>(cand, c, want, kth);
    case 2: return dropAndSum<2>(cand, c, want, kth);
    case 3: return dropAndSum<3>(cand, c, want, kth);
    case 4: return dropAndSum<4>(cand, c, want, kth);
    case 5: return dropAndSum<5>(cand, c, want, kth);
    case 6: return dropAndSum<6>(cand, c, want, kth);
    case 7: return dropAndSum<7>(cand, c, want, kth);
    case 8: return dropAndSum<8>(cand, c, want, kth);
    default: return selectMeanScalar(cand, c, want, kth);
  }
}

// By the sorting networks where the candidates fit in their 32 lanes (many first narrowed as
// selectMeanAvx2 narrows them), else by selectMeanAvx2.
__attribute__((target("avx512f,avx2,popcnt,bmi"))) double selectMeanAvx512(float* cand,
                                                                          std::size_t c,
                                                                          std::size_t want,
                                                                          float& kth) {
  if (c > 32 && c - want > 16) c = narrowAvx2(cand, c, want, kth);
  if (c <= 32) return selectMeanSorted(cand, c, want, kth);
  return selectMeanAvx2(cand, c, want, kth);
}

#endif

const SelectMeanFn pickedSelectMean = selectMeanVersions().front().fn;

// floor(v) as a 32-bit integer, v clamped to +-2^30 first: detail::floorToInt's value wherever
// a key fits (keyFits refuses the clamped ones), in arithmetic that vectorizes.
inline std::int32_t floorClamped(double v) {
  constexpr double kLimit = 1073741824.0;  // 2^30
  v = v > -kLimit ? v : -kLimit;           // (NaN too)
  v = v < kLimit ? v : kLimit;
  const auto t = static_cast<std::int32_t>(v);
  return t - (v < static_cast<double>(t) ? 1 : 0);
}

// The cell (cx, cy, cz)[f] of each point i = finite[f], f < n, in cells of edge 1 / inv_h
// anchored at (ox, oy, oz) (a point of the cloud): (x[i] - ox) in float, times inv_h in double,
// floored.
UPD_VECTOR_CLONES
void cellCoordsLoop(const float* __restrict x, const float* __restrict y, const float* __restrict z,
                const std::uint32_t* __restrict finite, std::size_t n, float ox, float oy,
                float oz, double inv_h, std::int32_t* __restrict cx, std::int32_t* __restrict cy,
                std::int32_t* __restrict cz) {
  for (std::size_t f = 0; f < n; ++f) {
    const std::uint32_t i = finite[f];
    cx[f] = floorClamped(static_cast<double>(x[i] - ox) * inv_h);
    cy[f] = floorClamped(static_cast<double>(y[i] - oy) * inv_h);
    cz[f] = floorClamped(static_cast<double>(z[i] - oz) * inv_h);
  }
}

// cellCoordsLoop where finite[f] = f (every point finite, as the voxel grid's centroids): no
// gathers.
UPD_VECTOR_CLONES
void cellCoordsDenseLoop(const float* __restrict x, const float* __restrict y,
                         const float* __restrict z, std::size_t n, float ox, float oy, float oz,
                         double inv_h, std::int32_t* __restrict cx, std::int32_t* __restrict cy,
                         std::int32_t* __restrict cz) {
  for (std::size_t i = 0; i < n; ++i) {
    cx[i] = floorClamped(static_cast<double>(x[i] - ox) * inv_h);
    cy[i] = floorClamped(static_cast<double>(y[i] - oy) * inv_h);
    cz[i] = floorClamped(static_cast<double>(z[i] - oz) * inv_h);
  }
}

#if defined(__GNUC__) && defined(__x86_64__)
// floorClamped((double(h) - r) * s) of the 4 lanes of h.
__attribute__((target("avx2"))) inline __m128i floorClamped4(__m128 h, __m256d s) {
  const __m256d lim = _mm256_set1_pd(1073741824.0), nlim = _mm256_set1_pd(-1073741824.0);
  // (max(v, -lim): v where v > -lim, else -lim, NaN too; min(v, lim): v where v < lim.)
  const __m256d v = _mm256_mul_pd(_mm256_cvtps_pd(h), s);
  return _mm256_cvttpd_epi32(_mm256_floor_pd(_mm256_min_pd(_mm256_max_pd(v, nlim), lim)));
}

// cellCoordsDense by AVX2 intrinsics, 8 points at a time (the rest by the loop).
__attribute__((target("avx2"))) void cellCoordsDenseAvx2(
    const float* __restrict x, const float* __restrict y, const float* __restrict z,
    std::size_t n, float ox, float oy, float oz, double inv_h, std::int32_t* __restrict cx,
    std::int32_t* __restrict cy, std::int32_t* __restrict cz) {
  const float* in[3] = {x, y, z};
  const float o[3] = {ox, oy, oz};
  std::int32_t* out[3] = {cx, cy, cz};
  const __m256d s = _mm256_set1_pd(inv_h);
  const std::size_t n8 = n / 8 * 8;
  for (int a = 0; a < 3; ++a) {
    const __m256 va = _mm256_set1_ps(o[a]);
    for (std::size_t i = 0; i < n8; i += 8) {
      const __m256 d = _mm256_sub_ps(_mm256_loadu_ps(in[a] + i), va);
      const __m256i c = _mm256_set_m128i(floorClamped4(_mm256_extractf128_ps(d, 1), s),
                                         floorClamped4(_mm256_castps256_ps128(d), s));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out[a] + i), c);
    }
  }
  cellCoordsDenseLoop(x + n8, y + n8, z + n8, n - n8, ox, oy, oz, inv_h, cx + n8, cy + n8,
                      cz + n8);
}

using CellCoordsDenseFn = void (*)(const float*, const float*, const float*, std::size_t, float,
                                   float, float, double, std::int32_t*, std::int32_t*,
                                   std::int32_t*);
CellCoordsDenseFn pickCellCoordsDense() {
  return cpuHasAvx2() ? cellCoordsDenseAvx2 : cellCoordsDenseLoop;
}
#else
using CellCoordsDenseFn = void (*)(const float*, const float*, const float*, std::size_t, float,
                                   float, float, double, std::int32_t*, std::int32_t*,
                                   std::int32_t*);
CellCoordsDenseFn pickCellCoordsDense() { return cellCoordsDenseLoop; }
#endif

const CellCoordsDenseFn pickedCellCoordsDense = pickCellCoordsDense();


}  // namespace

std::size_t gatherWithin(const float* x, const float* y, const float* z, std::size_t n, float qx,
                         float qy, float qz, float t, float* cand) {
  return pickedGatherWithin(x, y, z, n, qx, qy, qz, t, cand);
}

double selectMean(float* cand, std::size_t c, std::size_t want, float& kth) {
  return pickedSelectMean(cand, c, want, kth);
}

#if defined(__GNUC__) && defined(__x86_64__)
std::vector<KernelVersion<GatherWithinFn>> gatherWithinVersions() {
  return kernelVersions<GatherWithinFn>(gatherWithinAvx512, gatherWithinAvx2,
                                        gatherWithinScalar);
}

std::vector<KernelVersion<SelectMeanFn>> selectMeanVersions() {
  return kernelVersions<SelectMeanFn>(selectMeanAvx512, selectMeanAvx2,
                                      selectMeanScalar);
}
#else
std::vector<KernelVersion<GatherWithinFn>> gatherWithinVersions() {
  return {{gatherWithinScalar, "plain"}};
}
std::vector<KernelVersion<SelectMeanFn>> selectMeanVersions() {
  return {{selectMeanScalar, "plain"}};
}
#endif

std::size_t narrowCandidates(float* cand, std::size_t c, std::size_t want, float guess) {
#if defined(__GNUC__) && defined(__x86_64__)
  if (selectsSorted()) return narrowAvx2(cand, c, want, guess);
#endif
  (void)cand, (void)want, (void)guess;
  return c;
}

bool selectsSorted() {
#if defined(__GNUC__) && defined(__x86_64__)
  static const bool sorted = pickedSelectMean == selectMeanAvx512;
  return sorted;
#else
  return false;
#endif
}

UPD_VECTOR_CLONES
void minMax(const std::int32_t* __restrict v, std::size_t n, std::int32_t& lo, std::int32_t& hi) {
  std::int32_t l = v[0], h = v[0];
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t x = v[i];
    l = x < l ? x : l;  // (not std::min: GCC then keeps it scalar)
    h = x > h ? x : h;
  }
  lo = l, hi = h;
}

void cellCoords(const float* x, const float* y, const float* z, const std::uint32_t* finite,
                std::size_t n, float ox, float oy, float oz, double inv_h, std::int32_t* cx,
                std::int32_t* cy, std::int32_t* cz) {
  cellCoordsLoop(x, y, z, finite, n, ox, oy, oz, inv_h, cx, cy, cz);
}

void cellCoordsDense(const float* x, const float* y, const float* z, std::size_t n, float ox,
                     float oy, float oz, double inv_h, std::int32_t* cx, std::int32_t* cy,
                     std::int32_t* cz) {
  pickedCellCoordsDense(x, y, z, n, ox, oy, oz, inv_h, cx, cy, cz);
}

void cellCoordsDensePlain(const float* x, const float* y, const float* z, std::size_t n, float ox,
                          float oy, float oz, double inv_h, std::int32_t* cx, std::int32_t* cy,
                          std::int32_t* cz) {
  cellCoordsDenseLoop(x, y, z, n, ox, oy, oz, inv_h, cx, cy, cz);
}

void CellCoords::compute(const PointCloud& in, const std::vector<std::uint32_t>& finite,
                         double inv_h) {
  const std::size_t n = finite.size();
  x.resize(n), y.resize(n), z.resize(n);
  const std::uint32_t f0 = finite.front();
  const bool dense = n == in.size();  // (finite is then 0, 1, ..., n - 1)
  // (In static shares on the team: each point's cell by itself.)
#pragma omp parallel if (n > kTeamPoints)
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t b = RankedCells::share(n, team, me), e = RankedCells::share(n, team, me + 1);
    if (dense) {
      cellCoordsDense(in.x.data() + b, in.y.data() + b, in.z.data() + b, e - b, in.x[f0],
                      in.y[f0], in.z[f0], inv_h, x.data() + b, y.data() + b, z.data() + b);
    } else {
      cellCoords(in.x.data(), in.y.data(), in.z.data(), finite.data() + b, e - b, in.x[f0],
                 in.y[f0], in.z[f0], inv_h, x.data() + b, y.data() + b, z.data() + b);
    }
  }
}

void CellCoords::box(std::int32_t (&lo)[3], std::int32_t (&hi)[3]) const {
  const std::size_t n = x.size();
  const std::vector<std::int32_t>* axis[3] = {&x, &y, &z};
  std::int32_t l[3], h[3];
  for (int a = 0; a < 3; ++a) {
    l[a] = std::numeric_limits<std::int32_t>::max(), h[a] = std::numeric_limits<std::int32_t>::min();
  }
#pragma omp parallel if (n > kTeamPoints) reduction(min : l[:3]) reduction(max : h[:3])
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t b = RankedCells::share(n, team, me), e = RankedCells::share(n, team, me + 1);
    for (int a = 0; a < 3 && e > b; ++a) {
      std::int32_t share_lo = 0, share_hi = 0;
      minMax(axis[a]->data() + b, e - b, share_lo, share_hi);
      l[a] = std::min(l[a], share_lo), h[a] = std::max(h[a], share_hi);
    }
  }
  for (int a = 0; a < 3; ++a) lo[a] = l[a], hi[a] = h[a];
}

std::size_t CellCoords::countCells(const std::int32_t (&lo)[3], const std::int32_t (&hi)[3]) {
  const std::size_t n = x.size();
  if (marked.reset(lo, hi, 0, n)) {
#pragma omp parallel if (n > kTeamPoints)
    marked.buildTeam(n, [&](std::size_t f) { return marked.index(x[f], y[f], z[f]); });
    return marked.size();
  }
  CellMap cells(n / 4 + 64);
  for (std::size_t f = 0; f < n; ++f) {
    bool inserted = false;
    cells.findOrInsert(packKey(x[f], y[f], z[f]), inserted);
  }
  return cells.size();
}

}  // namespace upd::core::detail
