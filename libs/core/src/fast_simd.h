// Private to the fast paths: the arithmetic their vector loops (UPD_VECTOR_CLONES,
// upd/core/vector_clones.h) share. The fast path sources are built with -fno-math-errno
// (libs/core/CMakeLists.txt), so std::sqrt vectorizes there; rsqrtNewton serves where a
// reciprocal square root is what is wanted.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "upd/core/vector_clones.h"

namespace upd::core::detail {

/// A version of a kernel written once per instruction set, and its name ("AVX-512", "AVX2",
/// "plain"). Each such kernel lists the versions the running CPU can run: the one the library
/// calls first, the plain loop last (the tests compare every one).
template <class Fn>
struct KernelVersion {
  Fn fn;
  const char* name;
};

#if defined(__GNUC__) && defined(__x86_64__)
/// Whether the CPU runs the AVX2 kernels: AVX2 and the instructions their targets name beside it
/// (FMA, POPCNT, BMI's TZCNT), which every x86-64 CPU with AVX2 has; one test for all of them,
/// so that a CPU (or a hypervisor's mask) without one of the three takes the plain loops.
inline bool cpuHasAvx2() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
         __builtin_cpu_supports("popcnt") && __builtin_cpu_supports("bmi");
}

/// Whether the CPU runs the AVX-512 kernels (foundation, vector-length and doubleword
/// extensions: every AVX-512 CPU has the three).
inline bool cpuHasAvx512() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
         __builtin_cpu_supports("avx512dq");
}

/// The versions of a kernel the running CPU can run: avx512 where it has AVX-512 and AVX2, avx2
/// where it has AVX2 (cpuHasAvx2), plain.
template <class Fn>
std::vector<KernelVersion<Fn>> kernelVersions(Fn avx512, Fn avx2, Fn plain) {
  std::vector<KernelVersion<Fn>> v;
  const bool has_avx2 = cpuHasAvx2();
  if (has_avx2 && cpuHasAvx512()) v.push_back({avx512, "AVX-512"});
  if (has_avx2) v.push_back({avx2, "AVX2"});
  v.push_back({plain, "plain"});
  return v;
}
#endif

/// Lanes of the fixed-width inner loops (a multiple of every vector width used).
constexpr int kLanes = 16;

/// floor(v) as an integer: baseline x86-64 has no rounding instruction, and std::floor is then
/// a library call, a cost per point that this one-compare version avoids. v beyond +-4.6e18
/// (and NaN) is clamped first, so that the conversion stays defined and the caller's range check
/// of the result (keyFits) refuses the point: a coordinate of 1e30 m is an error, not undefined
/// behaviour.
inline std::int64_t floorToInt(double v) {
  constexpr double kLimit = 4.6e18;  // < 2^62
  v = v > -kLimit ? v : -kLimit;     // NaN goes to -kLimit
  v = v < kLimit ? v : kLimit;
  const auto t = static_cast<std::int64_t>(v);  // truncates towards zero
  return t - (v < static_cast<double>(t) ? 1 : 0);
}

/// The same for a float; clamped to +-2e9 (NaN to -2e9).
inline std::int32_t floorToInt32(float v) {
  constexpr float kLimit = 2.0e9f;  // < 2^31
  v = v > -kLimit ? v : -kLimit;
  v = v < kLimit ? v : kLimit;
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
  // In unsigned arithmetic: the same bits for every x, without the signed overflow a
  // non-positive x (-0, a rounding error below zero) would be.
  const std::uint32_t u = 0x5f375a86u - static_cast<std::uint32_t>(i >> 1);
  float y;
  std::memcpy(&y, &u, sizeof y);
  const float h = 0.5f * x;
  for (int s = 0; s < Steps; ++s) y = y * (1.5f - h * y * y);
  return y;
}

}  // namespace upd::core::detail
