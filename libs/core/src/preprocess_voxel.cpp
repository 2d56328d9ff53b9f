// The voxel grid in one pass over the input, a row at a time: first the cut-off and the voxel
// key of every point of the row in a vector loop (on AVX2 by intrinsics, 8 points at a time),
// then the sums, each point's voxel found from its left or upper neighbour's (organized frames:
// a voxel spans several pixels in a row and several rows) before the hash map is asked, the sums
// per voxel in point order. Its output is
// voxelDownsample's after cropRange, bit for bit (this file is built without contracting a
// multiply and an add into one rounding, so that the vector loop's range test is cropRange's).
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

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

using VoxelKeysFn = bool (*)(const float*, const float*, const float*, std::size_t,
                             const KeyPassParams&, std::uint64_t*, std::size_t&);
VoxelKeysFn pickVoxelKeys() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt") ? voxelKeysAvx2
                                                                            : voxelKeysLoop;
}
#else
using VoxelKeysFn = bool (*)(const float*, const float*, const float*, std::size_t,
                             const KeyPassParams&, std::uint64_t*, std::size_t&);
VoxelKeysFn pickVoxelKeys() { return voxelKeysLoop; }
#endif

const VoxelKeysFn pickedVoxelKeys = pickVoxelKeys();

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

using CropCopyFn = CropCounts (*)(const float*, const float*, const float*, std::size_t,
                                  const KeyPassParams&, float*, float*, float*);
CropCopyFn pickCropCopy() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt") ? cropCopyAvx2
                                                                            : cropCopyLoop;
}
#else
using CropCopyFn = CropCounts (*)(const float*, const float*, const float*, std::size_t,
                                  const KeyPassParams&, float*, float*, float*);
CropCopyFn pickCropCopy() { return cropCopyLoop; }
#endif

const CropCopyFn pickedCropCopy = pickCropCopy();

// Per voxel: the sums of the points relative to the anchor, of the colours (exact: below 2^32
// for any voxel of fewer than 2^24 points), and the count.
struct VoxelSums {
  double sx = 0, sy = 0, sz = 0;
  std::uint32_t r = 0, g = 0, b = 0;
  std::uint32_t n = 0;
};

// The per-thread buffers of voxelize, kept from call to call (no allocation in a warm loop).
struct VoxelScratch {
  CellMap map;
  std::vector<VoxelSums> voxels;
  std::vector<std::uint64_t> voxel_keys;  // the keys the map holds, by voxel id
  std::size_t held = 0;                   // (their number)
  std::size_t expected = 0;               // the voxels the map is sized for
  std::vector<std::uint64_t> row_key[2];  // the voxel key and id of each column, last two rows
  std::vector<std::uint32_t> row_id[2];
  std::vector<std::uint64_t> keys;  // the keys of the points of one row (unorganized: a chunk)
};

[[noreturn]] void throwSpan(double voxel_m) {
  throw std::invalid_argument(
      "PreprocessParams.voxel_m = " + std::to_string(voxel_m) +
      ": the cloud spans more than 2^20 voxels along an axis; use a larger voxel or a range "
      "cut-off");
}

// The first point of in that passes (finite, kept by test), or in.size(); the finite points
// before it added to finite.
std::size_t firstPassing(const PointCloud& in, const RangeBoxTest* test, std::size_t& finite) {
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (!in.isFinite(i)) continue;
    if (test == nullptr || test->keeps(in.point(i))) return i;
    ++finite;
  }
  return in.size();
}

// The centroids of s.voxels[0, n) (anchored at ref) into out, in voxel order.
void writeCentroids(const VoxelScratch& s, std::size_t n, const Eigen::Vector3d& ref,
                    bool colour, PointCloud& out) {
  out.resize(n, colour);
  out.width = n, out.height = 1;
  for (std::size_t v = 0; v < n; ++v) {
    const VoxelSums& a = s.voxels[v];
    const Eigen::Vector3d c = ref + Eigen::Vector3d(a.sx, a.sy, a.sz) / a.n;
    out.x[v] = static_cast<float>(c.x());
    out.y[v] = static_cast<float>(c.y());
    out.z[v] = static_cast<float>(c.z());
    if (colour) {
      // (lround's value: the quotient lies at least 1 / (2 n) from a half, far beyond its
      // rounding, and is not negative.)
      const auto avg = [&](std::uint32_t sum) {
        return static_cast<std::uint8_t>(static_cast<double>(sum) / a.n + 0.5);
      };
      out.r[v] = avg(a.r), out.g[v] = avg(a.g), out.b[v] = avg(a.b);
    }
  }
}

}  // namespace

bool voxelKeys(const float* x, const float* y, const float* z, std::size_t n,
               const KeyPassParams& k, std::uint64_t* keys, std::size_t& finite) {
  return pickedVoxelKeys(x, y, z, n, k, keys, finite);
}

bool voxelKeysPlain(const float* x, const float* y, const float* z, std::size_t n,
                    const KeyPassParams& k, std::uint64_t* keys, std::size_t& finite) {
  return voxelKeysLoop(x, y, z, n, k, keys, finite);
}

CropCounts cropCopy(const float* x, const float* y, const float* z, std::size_t n,
                    const KeyPassParams& k, float* ox, float* oy, float* oz) {
  return pickedCropCopy(x, y, z, n, k, ox, oy, oz);
}

CropCounts cropCopyPlain(const float* x, const float* y, const float* z, std::size_t n,
                         const KeyPassParams& k, float* ox, float* oy, float* oz) {
  return cropCopyLoop(x, y, z, n, k, ox, oy, oz);
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

namespace {

// One pass of voxelize: the sums of every passing point's voxel, in point order.
class VoxelPass {
 public:
  VoxelPass(VoxelScratch& s, const PointCloud& in, const Eigen::Vector3d& ref, double voxel_m,
            const PreprocessParams* p)
      : s_(s), in_(in), ref_(ref), voxel_m_(voxel_m) {
    k_ = rangeBoxBounds(p, in.sensor_origin);
    k_.ref_x = ref.x(), k_.ref_y = ref.y(), k_.ref_z = ref.z();
    k_.inv = 1.0 / voxel_m;
  }

  // Points [b, e) of one row (of an organized cloud: keys holds the row's voxel keys and ids
  // for the next row, above the previous row's; else both null).
  void row(std::size_t b, std::size_t e, std::uint64_t* keys, std::uint32_t* ids,
           const std::uint64_t* above_keys, const std::uint32_t* above_ids) {
    const std::size_t n = e - b;
    if (s_.keys.size() < n) s_.keys.resize(n);
    if (!keys) keys = s_.keys.data();
    if (!voxelKeys(&in_.x[b], &in_.y[b], &in_.z[b], n, k_, keys, finite_)) throwSpan(voxel_m_);
    const bool colour = in_.hasColor();
    const float *x = &in_.x[b], *y = &in_.y[b], *z = &in_.z[b];
    const std::uint8_t* rgb[3] = {colour ? &in_.r[b] : nullptr, colour ? &in_.g[b] : nullptr,
                                  colour ? &in_.b[b] : nullptr};
    std::size_t col = 0;
    while (col < n) {
      const std::uint64_t key = keys[col];
      if (key == kNoKey) {
        ++col;
        // (Holes and the cut-off background come in runs: passed 4 at a time, where all 4 are
        // kNoKey, that is where their AND is.)
        while (col + 4 <= n &&
               (keys[col] & keys[col + 1] & keys[col + 2] & keys[col + 3]) == kNoKey) {
          col += 4;
        }
        continue;
      }
      if (key != last_key_) {
        // The slot of the voxel kAhead points on fetched now, its look-up's load not waited for
        // then (a new voxel's slot is not in the cache).
        if (col + kAhead < n && keys[col + kAhead] != kNoKey) s_.map.prefetch(keys[col + kAhead]);
        // The pixel on the left (last_key_) or above mostly shares the voxel: no lookup.
        last_id_ = above_keys && above_keys[col] == key ? above_ids[col] : lookUp(key);
        last_key_ = key;
      }
      // A run of points in this voxel, its sums in registers from the voxel's and back: the
      // same additions in the same order as into the voxel point by point. (The colours are
      // integers, their sums exact in any order.)
      VoxelSums& a = s_.voxels[last_id_];
      double sx = a.sx, sy = a.sy, sz = a.sz;
      std::uint32_t sr = 0, sg = 0, sb = 0;
      std::size_t j = col;
      for (; j < n && keys[j] == key; ++j) {
        sx += static_cast<double>(x[j]) - ref_.x();
        sy += static_cast<double>(y[j]) - ref_.y();
        sz += static_cast<double>(z[j]) - ref_.z();
        if (ids) ids[j] = last_id_;
        if (colour) sr += rgb[0][j], sg += rgb[1][j], sb += rgb[2][j];
      }
      const auto run = static_cast<std::uint32_t>(j - col);
      a.sx = sx, a.sy = sy, a.sz = sz;
      a.n += run;
      if (colour) a.r += sr, a.g += sg, a.b += sb;
      passed_ += run;
      col = j;
    }
  }
  std::size_t passed() const { return passed_; }
  std::size_t finite() const { return finite_; }
  std::size_t voxels() const { return n_voxels_; }

 private:
  // (~16 runs of a Kinect frame's 1.9 points: a probe's miss under way when it is asked.)
  static constexpr std::size_t kAhead = 32;

  std::uint32_t lookUp(std::uint64_t key) {
    bool inserted = false;
    const std::uint32_t id = s_.map.findOrInsert(key, inserted);
    if (inserted) {
      if (s_.voxels.size() <= n_voxels_) {
        s_.voxels.resize(2 * n_voxels_ + 64), s_.voxel_keys.resize(2 * n_voxels_ + 64);
      }
      s_.voxel_keys[n_voxels_] = key;
      s_.voxels[n_voxels_++] = VoxelSums{};
      s_.held = n_voxels_;
    }
    return id;
  }

  VoxelScratch& s_;
  const PointCloud& in_;
  Eigen::Vector3d ref_;
  double voxel_m_;
  KeyPassParams k_;
  std::uint64_t last_key_ = kNoKey;
  std::uint32_t last_id_ = 0;
  std::size_t passed_ = 0, finite_ = 0, n_voxels_ = 0;
};

// voxelize with the calling thread's scratch s (a function of its own, kept from inlining and
// from specializing on its argument: GCC computes a thread_local's address again, by a call
// into the dynamic linker, at each use in a function that names it).
UPD_NOIPA CropCounts voxelizeWith(VoxelScratch& s, const PointCloud& in,
                                  double voxel_m, const RangeBoxTest* test,
                                  PointCloud& out) {
  out.sensor_origin = in.sensor_origin;
  std::size_t finite_before = 0;
  const std::size_t first = firstPassing(in, test, finite_before);
  if (first == in.size()) {
    writeCentroids(s, 0, Eigen::Vector3d::Zero(), false, out);
    return {finite_before, 0};
  }
  // Keys and centroids relative to the first point: exact far from the origin.
  const Eigen::Vector3d ref = in.point(first).cast<double>();
  // The table sized for the voxels of the last calls, not for the points: 64 Ki slots (1 MB)
  // for a Kinect frame's ~30,000 voxels instead of 256 Ki (4 MB) for a quarter of its pixels, a
  // table whose every new voxel's slot missed the cache. It grows within a call that has more
  // voxels and is kept until a call has fewer than half of what it was sized for (no new table
  // for every frame whose count crosses a power of two). (Where the keys fill less than a
  // quarter of it, only their slots are emptied.)
  if (s.held > s.expected || 2 * s.held < s.expected) {
    s.expected = std::max<std::size_t>(s.held, 1024);
  }
  s.map.clearHeld(s.expected, s.voxel_keys.data(), s.held);
  s.held = 0;
  VoxelPass pass(s, in, ref, voxel_m, test ? &test->params() : nullptr);
  if (!in.isOrganized()) {
    constexpr std::size_t kChunk = 4096;  // (the keys of a chunk stay in the cache)
    for (std::size_t b = first; b < in.size(); b += kChunk) {
      pass.row(b, std::min(in.size(), b + kChunk), nullptr, nullptr, nullptr, nullptr);
    }
  } else {
    const std::size_t w = in.width;
    for (int r = 0; r < 2; ++r) {
      s.row_key[r].assign(w, ~std::uint64_t(0));  // (no voxel has this key)
      s.row_id[r].resize(w);
    }
    for (std::size_t row = first / w; row < in.height; ++row) {
      const std::size_t cur = row & 1, above = cur ^ 1;
      // (The first row starts at the first passing point; the columns before it stay empty.)
      const std::size_t b = std::max(first, row * w), skip = b - row * w;
      pass.row(b, (row + 1) * w, s.row_key[cur].data() + skip, s.row_id[cur].data() + skip,
               s.row_key[above].data() + skip, s.row_id[above].data() + skip);
    }
  }
  writeCentroids(s, pass.voxels(), ref, in.hasColor(), out);
  return {finite_before + pass.finite(), pass.passed()};
}

}  // namespace

CropCounts voxelize(const PointCloud& in, double voxel_m, const RangeBoxTest* test,
                    PointCloud& out) {
  thread_local VoxelScratch s;
  return voxelizeWith(s, in, voxel_m, test, out);
}

void compactInPlace(PointCloud& c, const std::vector<char>& keep) {
  const bool colour = c.hasColor();
  std::size_t m = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!keep[i]) continue;
    c.x[m] = c.x[i], c.y[m] = c.y[i], c.z[m] = c.z[i];
    if (colour) c.r[m] = c.r[i], c.g[m] = c.g[i], c.b[m] = c.b[i];
    ++m;
  }
  c.x.resize(m), c.y.resize(m), c.z.resize(m);
  if (colour) c.r.resize(m), c.g.resize(m), c.b.resize(m);
  c.width = m, c.height = 1;
}

}  // namespace upd::core::detail
