// A compressed depth image (image_transport's compressedDepth plugin) on arbitrary bytes, as
// `upd ros` and bag playback decode it (depthFromCompressedDepth: the 12-byte header, then the
// PNG by libpng or the RVL stream). The input's first byte picks the format string (16UC1 or
// 32FC1, PNG or RVL), the rest is the message's data. Any input must give a depth image or a
// MessageError, never a crash, a hang, a sanitizer report or an allocation beyond the fuzzer's
// limit.
#include "fuzz_depth_check.h"
#include "upd/ros1/conversions.h"

#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kFormats[] = {
      "16UC1; compressedDepth png", "16UC1; compressedDepth rvl", "32FC1; compressedDepth png",
      "32FC1; compressedDepth rvl"};
  sensor_msgs::CompressedImage m;
  m.format = kFormats[data[0] % 4];
  m.data.assign(data + 1, data + size);
  try {
    upd::fuzz::requireSoundDepth(upd::ros1::depthFromCompressedDepth(m));
  } catch (const upd::ros1::MessageError&) {
    // a refused message: what the decoder must do with a bad one
  }
  return 0;
}
