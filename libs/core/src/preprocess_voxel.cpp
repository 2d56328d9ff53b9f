// The voxel grid's and the cut-off's vector kernels: the cut-off test and the voxel key of
// every point of a row in a vector loop (by intrinsics: 8 points at a time on AVX2, 16 on
// AVX-512), and the cut-off's copy of an organized frame. Their keys and tests are cropRange's,
// bit for bit (this file is built without contracting a multiply and an add into one rounding,
// so that the vector loop's range test is cropRange's). The sums are in
// preprocess_voxel_sums.cpp.
#include <algorithm>
#include <cmath>
#include <limits>

#include "fast_cell_map.h"
#include "fast_simd.h"
#include "preprocess_internal.h"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#endif

namespace upd::core::detail {

namespace {

// floor(v) as a 32-bit integer for |v| < 2^30, v clamped to +-2^30 first (keyFits then
// refuses it): floorToInt's value wherever a key fits.
inline std::int32_t floorClamped(double v) {
  constexpr double kLimit = 1073741824.0;  // 2^30
  v = v > -kLimit ? v : -kLimit;
  v = v < kLimit ? v : kLimit;
  const auto t = static_cast<std::int32_t>(v);
  return t - (v < static_cast<double>(t) ? 1 : 0);
}

// Finite, and kept by the range and box tests of k: RangeBoxTest's arithmetic, branch-free
// (& instead of &&), so that the loops calling it vectorize.
// All three finite, as 0 or 1: the tests joined by & on ints, not on bools (clang's
// -Wbitwise-instead-of-logical; the same code as & on the bools).
inline int finite3(float fx, float fy, float fz) {
  constexpr float kMaxF = std::numeric_limits<float>::max();
  return static_cast<int>(std::abs(fx) <= kMaxF) & static_cast<int>(std::abs(fy) <= kMaxF) &
         static_cast<int>(std::abs(fz) <= kMaxF);
}

inline bool passes(float fx, float fy, float fz, const KeyPassParams& k) {
  const bool finite = finite3(fx, fy, fz) != 0;
  const auto sx = static_cast<double>(fx - k.ox), sy = static_cast<double>(fy - k.oy),
             sz = static_cast<double>(fz - k.oz);
  const double d2 = (sx * sx + sy * sy) + sz * sz;  // (Eigen's squaredNorm of 3: the same)
  const bool in_range = (d2 >= k.rmin2) & (d2 <= k.rmax2);
  const bool in_box = (fx >= k.bx0) & (fy >= k.by0) & (fz >= k.bz0) & (fx <= k.bx1) &
                      (fy <= k.by1) & (fz <= k.bz1);
  return finite & in_range & in_box;
}

// voxelKeys (preprocess_internal.h), branch-free, so that it vectorizes.
UPD_VECTOR_CLONES
bool voxelKeysLoop(const float* __restrict x, const float* __restrict y, const float* __restrict z,
               std::size_t n, const KeyPassParams& k, std::uint64_t* __restrict keys,
               std::size_t& finite) {
  constexpr std::int32_t kBias = static_cast<std::int32_t>(kKeyBias);
  std::uint32_t bad = 0;
  std::size_t finite_count = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const float fx = x[j], fy = y[j], fz = z[j];
    const bool pass = passes(fx, fy, fz, k);
    finite_count += static_cast<std::size_t>(finite3(fx, fy, fz));
    const std::int32_t cx = floorClamped((static_cast<double>(fx) - k.ref_x) * k.inv);
    const std::int32_t cy = floorClamped((static_cast<double>(fy) - k.ref_y) * k.inv);
    const std::int32_t cz = floorClamped((static_cast<double>(fz) - k.ref_z) * k.inv);
    const bool fits = (cx >= -kBias) & (cx < kBias) & (cy >= -kBias) & (cy < kBias) &
                      (cz >= -kBias) & (cz < kBias);
    bad |= (pass & !fits) ? 1u : 0u;
    const std::uint64_t key = static_cast<std::uint64_t>(static_cast<std::uint32_t>(cx + kBias)) |
                              (static_cast<std::uint64_t>(static_cast<std::uint32_t>(cy + kBias)) << 21) |
                              (static_cast<std::uint64_t>(static_cast<std::uint32_t>(cz + kBias)) << 42);
    keys[j] = pass ? key : kNoKey;
  }
  finite += finite_count;
  return bad == 0;
}

// cropCopy (preprocess_internal.h), branch-free, so that it vectorizes: the point or NaN
// stored.
UPD_VECTOR_CLONES
CropCounts cropCopyLoop(const float* __restrict x, const float* __restrict y,
                        const float* __restrict z, std::size_t n, const KeyPassParams& k,
                        float* __restrict ox, float* __restrict oy, float* __restrict oz) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t finite_count = 0, kept = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const float fx = x[j], fy = y[j], fz = z[j];
    const bool pass = passes(fx, fy, fz, k);
    finite_count += static_cast<std::size_t>(finite3(fx, fy, fz));
    kept += pass ? 1 : 0;
    ox[j] = pass ? fx : nan;
    oy[j] = pass ? fy : nan;
    oz[j] = pass ? fz : nan;
  }
  return {finite_count, kept};
}

#if defined(__GNUC__) && defined(__x86_64__)
// The 4-lane double masks lo and hi as one 8-lane 32-bit mask.
__attribute__((target("avx2"))) inline __m256i packMasks(__m256d lo, __m256d hi) {
  const __m256i even = _mm256_setr_epi32(0, 2, 4, 6, 0, 2, 4, 6);
  const __m128i l = _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(lo), even));
  const __m128i h = _mm256_castsi256_si128(_mm256_permutevar8x32_epi32(_mm256_castpd_si256(hi), even));
  return _mm256_set_m128i(h, l);
}

// floorClamped((double(h) - r) * s) of the 4 lanes of h (the floor of the clamped value: the
// same integer as its truncation less one where that exceeds it).
__attribute__((target("avx2"))) inline __m128i cellCoords4(__m128 h, __m256d r, __m256d s) {
  const __m256d lim = _mm256_set1_pd(1073741824.0), nlim = _mm256_set1_pd(-1073741824.0);
  // (max(v, -lim): v where v > -lim, else -lim, NaN too; min(v, lim): v where v < lim.)
  const __m256d v = (_mm256_cvtps_pd(h) - r) * s;
  return _mm256_cvttpd_epi32(_mm256_floor_pd(_mm256_min_pd(_mm256_max_pd(v, nlim), lim)));
}

// cellCoords4 of the 8 lanes of f.
__attribute__((target("avx2"))) inline __m256i cellCoords(__m256 f, double ref, double inv) {
  const __m256d r = _mm256_set1_pd(ref), s = _mm256_set1_pd(inv);
  return _mm256_set_m128i(cellCoords4(_mm256_extractf128_ps(f, 1), r, s),
                          cellCoords4(_mm256_castps256_ps128(f), r, s));
}

// The range test of 4 lanes (offsets from the origin in float): the squared norm in double as
// (x^2 + y^2) + z^2, within [rmin2, rmax2].
__attribute__((target("avx2"))) inline __m256d rangeMask4(__m128 hx, __m128 hy, __m128 hz,
                                                          __m256d rmin2, __m256d rmax2) {
  const __m256d sx = _mm256_cvtps_pd(hx), sy = _mm256_cvtps_pd(hy), sz = _mm256_cvtps_pd(hz);
  const __m256d d2 = (sx * sx + sy * sy) + sz * sz;
  return _mm256_and_pd(_mm256_cmp_pd(d2, rmin2, _CMP_GE_OQ), _mm256_cmp_pd(d2, rmax2, _CMP_LE_OQ));
}

// The range test's 8-lane mask, the offsets from the origin taken in float.
__attribute__((target("avx2"))) inline __m256i rangeMask(__m256 fx, __m256 fy, __m256 fz,
                                                         const KeyPassParams& k) {
  const __m256 dx = fx - _mm256_set1_ps(k.ox), dy = fy - _mm256_set1_ps(k.oy),
               dz = fz - _mm256_set1_ps(k.oz);
  const __m256d rmin2 = _mm256_set1_pd(k.rmin2), rmax2 = _mm256_set1_pd(k.rmax2);
  return packMasks(rangeMask4(_mm256_castps256_ps128(dx), _mm256_castps256_ps128(dy),
                              _mm256_castps256_ps128(dz), rmin2, rmax2),
                   rangeMask4(_mm256_extractf128_ps(dx, 1), _mm256_extractf128_ps(dy, 1),
                              _mm256_extractf128_ps(dz, 1), rmin2, rmax2));
}

// The low (h = 0) or high 4 lanes of v.
__attribute__((target("avx2"))) inline __m128i lanes4(__m256i v, int h) {
  return h ? _mm256_extracti128_si256(v, 1) : _mm256_castsi256_si128(v);
}

// The keys of 4 lanes: (x, y, z) biased into 21 bits each, kNoKey where pass is 0.
__attribute__((target("avx2"))) inline __m256i packKeys(__m128i ux, __m128i uy, __m128i uz,
                                                        __m128i pass) {
  const __m256i key = _mm256_or_si256(
      _mm256_cvtepu32_epi64(ux),
      _mm256_or_si256(_mm256_slli_epi64(_mm256_cvtepu32_epi64(uy), 21),
                      _mm256_slli_epi64(_mm256_cvtepu32_epi64(uz), 42)));
  return _mm256_or_si256(key, _mm256_xor_si256(_mm256_cvtepi32_epi64(pass), _mm256_set1_epi64x(-1)));
}

// voxelKeys by AVX2 intrinsics, 8 points at a time (the rest by the loop): the same operations
// in double and float as voxelKeysLoop, so the same keys.
__attribute__((target("avx2,popcnt"))) bool voxelKeysAvx2(const float* __restrict x,
                                                          const float* __restrict y,
                                                          const float* __restrict z, std::size_t n,
                                                          const KeyPassParams& k,
                                                          std::uint64_t* __restrict keys,
                                                          std::size_t& finite) {
  const __m256 maxf = _mm256_set1_ps(std::numeric_limits<float>::max());
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 b0[3] = {_mm256_set1_ps(k.bx0), _mm256_set1_ps(k.by0), _mm256_set1_ps(k.bz0)};
  const __m256 b1[3] = {_mm256_set1_ps(k.bx1), _mm256_set1_ps(k.by1), _mm256_set1_ps(k.bz1)};
  const __m256i lo = _mm256_set1_epi32(-static_cast<std::int32_t>(kKeyBias) - 1);
  const __m256i hi = _mm256_set1_epi32(static_cast<std::int32_t>(kKeyBias));
  __m256i bad = _mm256_setzero_si256();
  std::size_t finite_count = 0;
  const std::size_t n8 = n / 8 * 8;
  for (std::size_t j = 0; j < n8; j += 8) {
    const __m256 f[3] = {_mm256_loadu_ps(x + j), _mm256_loadu_ps(y + j), _mm256_loadu_ps(z + j)};
    __m256 fin = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    for (int a = 0; a < 3; ++a) {
      fin = _mm256_and_ps(fin, _mm256_cmp_ps(_mm256_and_ps(f[a], abs_mask), maxf, _CMP_LE_OQ));
    }
    finite_count += static_cast<std::size_t>(
        __builtin_popcount(static_cast<unsigned>(_mm256_movemask_ps(fin))));
    __m256 ok = _mm256_and_ps(fin, _mm256_castsi256_ps(rangeMask(f[0], f[1], f[2], k)));
    for (int a = 0; a < 3; ++a) {
      ok = _mm256_and_ps(ok, _mm256_and_ps(_mm256_cmp_ps(f[a], b0[a], _CMP_GE_OQ),
                                           _mm256_cmp_ps(f[a], b1[a], _CMP_LE_OQ)));
    }
    if (_mm256_testz_ps(ok, ok)) {  // (none passes, as in the NaN holes and beyond the range)
      const __m256i none = _mm256_set1_epi64x(static_cast<long long>(kNoKey));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(keys + j), none);
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(keys + j + 4), none);
      continue;
    }
    __m256i fits = _mm256_set1_epi32(-1), u[3];
    const double ref[3] = {k.ref_x, k.ref_y, k.ref_z};
    for (int a = 0; a < 3; ++a) {
      const __m256i c = cellCoords(f[a], ref[a], k.inv);
      fits = _mm256_and_si256(fits, _mm256_and_si256(_mm256_cmpgt_epi32(c, lo), _mm256_cmpgt_epi32(hi, c)));
      u[a] = _mm256_add_epi32(c, hi);
    }
    const __m256i pass = _mm256_castps_si256(ok);
    bad = _mm256_or_si256(bad, _mm256_andnot_si256(fits, pass));
    for (int h = 0; h < 2; ++h) {
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(keys + j + 4 * h),
                          packKeys(lanes4(u[0], h), lanes4(u[1], h), lanes4(u[2], h),
                                   lanes4(pass, h)));
    }
  }
  finite += finite_count;
  const bool rest = voxelKeysLoop(x + n8, y + n8, z + n8, n - n8, k, keys + n8, finite);
  return rest && _mm256_testz_si256(bad, bad);
}

// (GCC 12.2 warns that the unmasked AVX-512 intrinsics read an uninitialized value: their
// pass-through operand is _mm512_undefined_pd() by design; a false positive.)
#pragma GCC diagnostic push
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// cellCoords4 of 8 lanes on AVX-512: the same clamp (a NaN lane takes -2^30, max's second
// operand), floor and truncation, in 8 doubles.
__attribute__((target("avx512f"))) inline __m256i cellCoords8(__m256 h, double ref, double inv) {
  const __m512d lim = _mm512_set1_pd(1073741824.0), nlim = _mm512_set1_pd(-1073741824.0);
  const __m512d v = _mm512_mul_pd(_mm512_sub_pd(_mm512_cvtps_pd(h), _mm512_set1_pd(ref)),
                                  _mm512_set1_pd(inv));
  const __m512d c = _mm512_min_pd(_mm512_max_pd(v, nlim), lim);
  return _mm512_cvttpd_epi32(_mm512_roundscale_pd(c, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC));
}

// The range test of 8 lanes (offsets from the origin in float), rangeMask4's arithmetic.
__attribute__((target("avx512f"))) inline __mmask8 rangeMask8(__m256 hx, __m256 hy, __m256 hz,
                                                             const KeyPassParams& k) {
  const __m512d sx = _mm512_cvtps_pd(hx), sy = _mm512_cvtps_pd(hy), sz = _mm512_cvtps_pd(hz);
  const __m512d d2 = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(sx, sx), _mm512_mul_pd(sy, sy)),
                                   _mm512_mul_pd(sz, sz));
  return _mm512_cmp_pd_mask(d2, _mm512_set1_pd(k.rmin2), _CMP_GE_OQ) &
         _mm512_cmp_pd_mask(d2, _mm512_set1_pd(k.rmax2), _CMP_LE_OQ);
}

// The tests of 16 points on AVX-512: fin, all three coordinates finite; pass, finite and kept
// by the box and range tests (voxelKeysAvx2's tests, lane for lane).
struct Tests16 {
  __mmask16 fin, pass;
};
__attribute__((target("avx512f,avx512vl,avx512dq"))) inline Tests16 tests16(const __m512 (&f)[3],
                                                                           const KeyPassParams& k) {
  const __m512 maxf = _mm512_set1_ps(std::numeric_limits<float>::max());
  const float b0[3] = {k.bx0, k.by0, k.bz0}, b1[3] = {k.bx1, k.by1, k.bz1}, o[3] = {k.ox, k.oy, k.oz};
  __mmask16 fin = 0xFFFF, pass = 0xFFFF;
  __m512 d[3];
  for (int a = 0; a < 3; ++a) {
    fin &= _mm512_cmp_ps_mask(_mm512_abs_ps(f[a]), maxf, _CMP_LE_OQ);
    pass &= _mm512_cmp_ps_mask(f[a], _mm512_set1_ps(b0[a]), _CMP_GE_OQ) &
            _mm512_cmp_ps_mask(f[a], _mm512_set1_ps(b1[a]), _CMP_LE_OQ);
    d[a] = _mm512_sub_ps(f[a], _mm512_set1_ps(o[a]));
  }
  const auto range = static_cast<__mmask16>(
      rangeMask8(_mm512_castps512_ps256(d[0]), _mm512_castps512_ps256(d[1]),
                 _mm512_castps512_ps256(d[2]), k) |
      rangeMask8(_mm512_extractf32x8_ps(d[0], 1), _mm512_extractf32x8_ps(d[1], 1),
                 _mm512_extractf32x8_ps(d[2], 1), k) << 8);
  return {fin, static_cast<__mmask16>(pass & fin & range)};
}

// The 8 keys of half h of 16 points (f: their coordinates, pass: the 8 lanes' tests), kNoKey
// where a lane fails; the lanes whose keys overflow added to bad.
__attribute__((target("avx512f,avx512vl,avx512dq"))) inline __m512i keys8(const __m512 (&f)[3], int h,
                                                       const KeyPassParams& k, __mmask8 pass,
                                                       __mmask8& bad) {
  const double ref[3] = {k.ref_x, k.ref_y, k.ref_z};
  const __m256i lo = _mm256_set1_epi32(-static_cast<std::int32_t>(kKeyBias) - 1);
  const __m256i hi = _mm256_set1_epi32(static_cast<std::int32_t>(kKeyBias));
  __mmask8 fits = 0xFF;
  __m512i key = _mm512_setzero_si512();
  for (int a = 0; a < 3; ++a) {
    const __m256 half = h ? _mm512_extractf32x8_ps(f[a], 1) : _mm512_castps512_ps256(f[a]);
    const __m256i c = cellCoords8(half, ref[a], k.inv);
    fits &= _mm256_cmpgt_epi32_mask(c, lo) & _mm256_cmpgt_epi32_mask(hi, c);
    const __m512i u = _mm512_cvtepu32_epi64(_mm256_add_epi32(c, hi));
    key = _mm512_or_si512(key, _mm512_slli_epi64(u, static_cast<unsigned>(21 * a)));
  }
  bad |= static_cast<__mmask8>(pass & ~fits);
  return _mm512_mask_blend_epi64(pass, _mm512_set1_epi64(static_cast<long long>(kNoKey)), key);
}

// voxelKeys on AVX-512, 16 points at a time (the rest by the loop): voxelKeysAvx2's tests and
// arithmetic in wider vectors, so the same keys.
__attribute__((target("avx512f,avx512vl,avx512dq,popcnt"))) bool voxelKeysAvx512(
    const float* __restrict x, const float* __restrict y, const float* __restrict z,
    std::size_t n, const KeyPassParams& k, std::uint64_t* __restrict keys, std::size_t& finite) {
  __mmask8 bad = 0;
  std::size_t finite_count = 0;
  const std::size_t n16 = n / 16 * 16;
  for (std::size_t j = 0; j < n16; j += 16) {
    const __m512 f[3] = {_mm512_loadu_ps(x + j), _mm512_loadu_ps(y + j), _mm512_loadu_ps(z + j)};
    const Tests16 t = tests16(f, k);
    finite_count += static_cast<std::size_t>(__builtin_popcount(t.fin));
    const __mmask16 ok = t.pass;
    if (ok == 0) {  // (none passes, as in the NaN holes and beyond the range)
      const __m512i none = _mm512_set1_epi64(static_cast<long long>(kNoKey));
      _mm512_storeu_si512(keys + j, none), _mm512_storeu_si512(keys + j + 8, none);
      continue;
    }
    for (int h = 0; h < 2; ++h) {
      _mm512_storeu_si512(keys + j + 8 * h,
                          keys8(f, h, k, static_cast<__mmask8>(ok >> (8 * h)), bad));
    }
  }
  finite += finite_count;
  const bool rest = voxelKeysAvx2(x + n16, y + n16, z + n16, n - n16, k, keys + n16, finite);
  return rest && bad == 0;
}

#pragma GCC diagnostic pop

#endif

const VoxelKeysFn pickedVoxelKeys = voxelKeysVersions().front().fn;

#if defined(__GNUC__) && defined(__x86_64__)
// cropCopy by AVX2 intrinsics, 8 points at a time (the rest by the loop): voxelKeysAvx2's tests,
// hence cropCopyLoop's output.
__attribute__((target("avx2,popcnt"))) CropCounts cropCopyAvx2(
    const float* __restrict x, const float* __restrict y, const float* __restrict z,
    std::size_t n, const KeyPassParams& k, float* __restrict ox, float* __restrict oy,
    float* __restrict oz) {
  const __m256 maxf = _mm256_set1_ps(std::numeric_limits<float>::max());
  const __m256 abs_mask = _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff));
  const __m256 nan = _mm256_set1_ps(std::numeric_limits<float>::quiet_NaN());
  const __m256 b0[3] = {_mm256_set1_ps(k.bx0), _mm256_set1_ps(k.by0), _mm256_set1_ps(k.bz0)};
  const __m256 b1[3] = {_mm256_set1_ps(k.bx1), _mm256_set1_ps(k.by1), _mm256_set1_ps(k.bz1)};
  float* const out[3] = {ox, oy, oz};
  std::size_t finite_count = 0, kept = 0;
  const std::size_t n8 = n / 8 * 8;
  for (std::size_t j = 0; j < n8; j += 8) {
    const __m256 f[3] = {_mm256_loadu_ps(x + j), _mm256_loadu_ps(y + j), _mm256_loadu_ps(z + j)};
    __m256 finite = _mm256_castsi256_ps(_mm256_set1_epi32(-1));
    __m256 in_box = finite;
    for (int a = 0; a < 3; ++a) {
      finite = _mm256_and_ps(finite, _mm256_cmp_ps(_mm256_and_ps(f[a], abs_mask), maxf, _CMP_LE_OQ));
      in_box = _mm256_and_ps(in_box, _mm256_and_ps(_mm256_cmp_ps(f[a], b0[a], _CMP_GE_OQ),
                                                   _mm256_cmp_ps(f[a], b1[a], _CMP_LE_OQ)));
    }
    const __m256 pass = _mm256_and_ps(
        _mm256_and_ps(finite, in_box), _mm256_castsi256_ps(rangeMask(f[0], f[1], f[2], k)));
    finite_count += static_cast<std::size_t>(__builtin_popcount(
        static_cast<unsigned>(_mm256_movemask_ps(finite))));
    kept += static_cast<std::size_t>(
        __builtin_popcount(static_cast<unsigned>(_mm256_movemask_ps(pass))));
    for (int a = 0; a < 3; ++a) _mm256_storeu_ps(out[a] + j, _mm256_blendv_ps(nan, f[a], pass));
  }
  const CropCounts rest = cropCopyLoop(x + n8, y + n8, z + n8, n - n8, k, ox + n8, oy + n8, oz + n8);
  return {finite_count + rest.finite, kept + rest.kept};
}

#pragma GCC diagnostic push
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wuninitialized"  // (as for voxelKeysAvx512)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
// cropCopy on AVX-512, 16 points at a time (the rest by cropCopyAvx2): voxelKeysAvx512's tests,
// hence cropCopyLoop's output.
__attribute__((target("avx512f,avx512vl,avx512dq,popcnt"))) CropCounts cropCopyAvx512(
    const float* __restrict x, const float* __restrict y, const float* __restrict z,
    std::size_t n, const KeyPassParams& k, float* __restrict ox, float* __restrict oy,
    float* __restrict oz) {
  const __m512 nan = _mm512_set1_ps(std::numeric_limits<float>::quiet_NaN());
  float* const out[3] = {ox, oy, oz};
  std::size_t finite_count = 0, kept = 0;
  const std::size_t n16 = n / 16 * 16;
  for (std::size_t j = 0; j < n16; j += 16) {
    const __m512 f[3] = {_mm512_loadu_ps(x + j), _mm512_loadu_ps(y + j), _mm512_loadu_ps(z + j)};
    const Tests16 t = tests16(f, k);
    const __mmask16 pass = t.pass;
    finite_count += static_cast<std::size_t>(__builtin_popcount(t.fin));
    kept += static_cast<std::size_t>(__builtin_popcount(pass));
    for (int a = 0; a < 3; ++a) _mm512_storeu_ps(out[a] + j, _mm512_mask_blend_ps(pass, nan, f[a]));
  }
  const CropCounts rest =
      cropCopyAvx2(x + n16, y + n16, z + n16, n - n16, k, ox + n16, oy + n16, oz + n16);
  return {finite_count + rest.finite, kept + rest.kept};
}
#pragma GCC diagnostic pop

#endif

const CropCopyFn pickedCropCopy = cropCopyVersions().front().fn;

}  // namespace

#if defined(__GNUC__) && defined(__x86_64__)
std::vector<KernelVersion<VoxelKeysFn>> voxelKeysVersions() {
  return kernelVersions<VoxelKeysFn>(voxelKeysAvx512, voxelKeysAvx2, voxelKeysLoop);
}

std::vector<KernelVersion<CropCopyFn>> cropCopyVersions() {
  return kernelVersions<CropCopyFn>(cropCopyAvx512, cropCopyAvx2, cropCopyLoop);
}
#else
std::vector<KernelVersion<VoxelKeysFn>> voxelKeysVersions() { return {{voxelKeysLoop, "plain"}}; }
std::vector<KernelVersion<CropCopyFn>> cropCopyVersions() { return {{cropCopyLoop, "plain"}}; }
#endif

bool voxelKeys(const float* x, const float* y, const float* z, std::size_t n,
               const KeyPassParams& k, std::uint64_t* keys, std::size_t& finite) {
  return pickedVoxelKeys(x, y, z, n, k, keys, finite);
}

CropCounts cropCopy(const float* x, const float* y, const float* z, std::size_t n,
                    const KeyPassParams& k, float* ox, float* oy, float* oz) {
  return pickedCropCopy(x, y, z, n, k, ox, oy, oz);
}

KeyPassParams rangeBoxBounds(const PreprocessParams* p, const Eigen::Vector3f& sensor_origin) {
  KeyPassParams k{};
  k.ox = sensor_origin.x(), k.oy = sensor_origin.y(), k.oz = sensor_origin.z();
  const bool range = p && p->range_enabled, box = p && p->box_enabled;
  const double inf = std::numeric_limits<double>::infinity();
  const float inf_f = std::numeric_limits<float>::infinity();
  k.rmin2 = range ? p->range_min_m * p->range_min_m : -inf;
  k.rmax2 = range ? p->range_max_m * p->range_max_m : inf;
  const Eigen::Vector3f lo = box ? p->box_min_m : Eigen::Vector3f::Constant(-inf_f);
  const Eigen::Vector3f hi = box ? p->box_max_m : Eigen::Vector3f::Constant(inf_f);
  k.bx0 = lo.x(), k.by0 = lo.y(), k.bz0 = lo.z();
  k.bx1 = hi.x(), k.by1 = hi.y(), k.bz1 = hi.z();
  return k;
}

}  // namespace upd::core::detail
