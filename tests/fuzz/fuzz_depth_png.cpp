// A depth PNG on arbitrary bytes, as `upd analyze --intrinsics` and TUM folders read it
// (readDepthPng: our signature and header checks, then libpng with our handlers). Any input must
// give a depth image or a std::runtime_error, never a crash, a hang, a sanitizer report or an
// allocation beyond the fuzzer's limit.
#include "fuzz_depth_check.h"
#include "fuzz_input.h"

#include "upd/mrpt_bridge/depth_files.h"

#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string png = upd::fuzz::inputPath(".png");
  upd::fuzz::writeInput(png, data, size);
  try {
    upd::fuzz::requireSoundDepth(upd::mrpt_bridge::readDepthPng(png));
  } catch (const std::runtime_error&) {
    // a refused file: what the reader must do with a bad one
  }
  return 0;
}
