// What every depth image a decoder returns must be (the depth PNG and compressed depth fuzzers):
// a size of at least one pixel, a value for each, every value finite and not negative (0 is no
// return). Anything else traps, which libFuzzer reports as a crash.
#pragma once

#include "upd/core/camera.h"

#include <cmath>
#include <cstddef>

namespace upd::fuzz {

inline void requireSoundDepth(const core::DepthImage& d) {
  if (d.width <= 0 || d.height <= 0) __builtin_trap();
  if (d.depth_m.size() != static_cast<std::size_t>(d.width) * d.height) __builtin_trap();
  for (const float z : d.depth_m) {
    if (!(z >= 0.f) || !std::isfinite(z)) __builtin_trap();
  }
}

}  // namespace upd::fuzz
