// Private to the fast paths: what lets their inner loops use the machine's vector units.
//
// The library is compiled for the baseline x86-64 (SSE2) so that it runs anywhere. The few
// loops that dominate the fast paths are written branch-free over fixed-width lanes and marked
// UPD_VECTOR_CLONES: GCC then compiles them three times (AVX-512, AVX2 + FMA, baseline) and
// picks the version for the running CPU when the program loads. std::sqrt keeps a loop scalar
// unless the whole build sets -fno-math-errno, so the loops use rsqrtNewton instead.
#pragma once

#include <cstdint>
#include <cstring>

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define UPD_VECTOR_CLONES \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define UPD_VECTOR_CLONES
#endif

namespace upd::detail {

/// Lanes of the fixed-width inner loops (a multiple of every vector width used).
constexpr int kLanes = 16;

/// floor(v) as an integer: baseline x86-64 has no rounding instruction, and std::floor is then
/// a library call, a cost per point that this one-compare version avoids.
inline std::int64_t floorToInt(double v) {
  const auto t = static_cast<std::int64_t>(v);  // truncates towards zero
  return t - (v < static_cast<double>(t) ? 1 : 0);
}

/// The same for a float with |v| < 2^31.
inline std::int32_t floorToInt32(float v) {
  const auto t = static_cast<std::int32_t>(v);  // truncates towards zero
  return t - (v < static_cast<float>(t) ? 1 : 0);
}

/// 1 / sqrt(x) for x > 0: the bit-level first guess and Steps Newton steps, plain arithmetic
/// that vectorizes. Three steps reach float precision (relative error < 2e-7); two give 1e-5,
/// enough for the lattice sums, whose inputs (cell moments) carry far larger errors.
template <int Steps = 3>
inline float rsqrtNewton(float x) {
  std::int32_t i;
  std::memcpy(&i, &x, sizeof i);
  i = 0x5f375a86 - (i >> 1);
  float y;
  std::memcpy(&y, &i, sizeof y);
  const float h = 0.5f * x;
  for (int s = 0; s < Steps; ++s) y = y * (1.5f - h * y * y);
  return y;
}

}  // namespace upd::detail
