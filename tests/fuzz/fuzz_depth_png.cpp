// A depth PNG on arbitrary bytes, as `upd analyze --intrinsics` and TUM folders read it
// (readDepthPng: our signature and header checks, then libpng with our handlers). Any input must
// give a depth image or a std::runtime_error, never a crash, a hang, a sanitizer report or an
// allocation beyond the fuzzer's limit.
#include "fuzz_input.h"

#include "upd/mrpt_bridge/depth_files.h"

#include <cmath>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string png = upd::fuzz::inputPath(".png");
  upd::fuzz::writeInput(png, data, size);
  try {
    const upd::core::DepthImage d = upd::mrpt_bridge::readDepthPng(png);
    if (d.width <= 0 || d.height <= 0) __builtin_trap();
    if (d.depth_m.size() != static_cast<std::size_t>(d.width) * d.height) __builtin_trap();
    for (const float z : d.depth_m) {
      if (!(z >= 0.f) || !std::isfinite(z)) __builtin_trap();
    }
  } catch (const std::runtime_error&) {
    // a refused file: what the reader must do with a bad one
  }
  return 0;
}
