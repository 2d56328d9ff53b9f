// A depth camera's calibration YAML on arbitrary bytes (loadDepthCalibration: our text checks,
// OpenCV's YAML parser, then our fields). Any input must give a calibration or a
// std::runtime_error, never a crash, a hang or a sanitizer report. OpenCV 4.6's parser loops
// forever on some malformed documents: the text checks refuse those found so far
// (regressions/calibration), and this target, run by hand, hunts for more (it is not in CI's
// bounded run, where a new one would fail an unrelated change).
#include "fuzz_input.h"

#include "upd/mrpt_bridge/depth_files.h"

#include <cmath>
#include <stdexcept>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string yaml = upd::fuzz::inputPath(".yaml");
  upd::fuzz::writeInput(yaml, data, size);
  try {
    const upd::mrpt_bridge::DepthCalibration c = upd::mrpt_bridge::loadDepthCalibration(yaml);
    if (!(c.K.fx > 0) || !(c.K.fy > 0) || c.K.width <= 0 || c.K.height <= 0) __builtin_trap();
    if (!std::isfinite(c.K.cx) || !std::isfinite(c.K.cy)) __builtin_trap();
  } catch (const std::runtime_error&) {
    // a refused file: what the reader must do with a bad one
  }
  return 0;
}
