// A compressed depth image as image_transport's compressedDepth plugin writes it (its
// encodeCompressedDepthImage and RvlCodec::CompressRVL, written again here: Debian packages no
// compressed_depth_image_transport): for the tests of depthFromCompressedDepth, of bags holding
// such images, and the bag fuzzer's seeds.
#pragma once

#include "upd/core/camera.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sensor_msgs/CompressedImage.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace upd::test {

/// The plugin's RVL code of codes (zeros and non-zeros counted in runs, the non-zeros as the
/// zigzag of their difference to the one before, each a variable-length run of 3-bit nibbles).
inline std::vector<std::uint8_t> rvlOf(const std::vector<std::uint16_t>& codes) {
  std::vector<std::uint32_t> words;
  std::uint32_t word = 0;
  int nibbles = 0;
  const auto put = [&](std::uint32_t value) {
    do {
      std::uint32_t nibble = value & 7u;
      if (value >>= 3) nibble |= 8u;
      word = (word << 4) | nibble;
      if (++nibbles == 8) words.push_back(word), word = 0, nibbles = 0;
    } while (value);
  };
  std::uint16_t previous = 0;
  for (std::size_t i = 0; i < codes.size();) {
    std::uint32_t zeros = 0, nonzeros = 0;
    for (; i < codes.size() && codes[i] == 0; ++i) ++zeros;
    put(zeros);
    for (std::size_t j = i; j < codes.size() && codes[j] != 0; ++j) ++nonzeros;
    put(nonzeros);
    for (std::uint32_t k = 0; k < nonzeros; ++k, ++i) {
      const int delta = static_cast<int>(codes[i]) - previous;
      // (The plugin's (delta << 1) ^ (delta >> 31), in unsigned arithmetic: no shift of a
      // negative value.)
      put((static_cast<std::uint32_t>(delta) << 1) ^ (delta < 0 ? 0xffffffffu : 0u));
      previous = codes[i];
    }
  }
  if (nibbles) words.push_back(word << 4 * (8 - nibbles));
  std::vector<std::uint8_t> bytes(words.size() * 4);
  if (!words.empty()) std::memcpy(bytes.data(), words.data(), bytes.size());
  return bytes;
}

/// depth [m] as the plugin compresses it: encoding "16UC1" (millimetres, beyond depth_max_m 0)
/// or "32FC1" (inverse depth: code = A / depth + B, A = q (q + 1), B = 1 - A / depth_max_m, q
/// the plugin's depth_quantization; beyond depth_max_m or without a range 0), codec "png" or
/// "rvl".
inline sensor_msgs::CompressedImage compressedDepthOf(const core::DepthImage& depth,
                                                      const std::string& encoding,
                                                      const std::string& codec,
                                                      float depth_max_m = 10.f,
                                                      float depth_quantization = 100.f) {
  const bool mm = encoding == "16UC1";
  const float a = depth_quantization * (depth_quantization + 1.f);
  const float b = 1.f - a / depth_max_m;
  std::vector<std::uint16_t> codes(depth.depth_m.size());
  for (std::size_t i = 0; i < codes.size(); ++i) {
    const float d = depth.depth_m[i];
    const bool valid = d > 0 && d < depth_max_m;
    codes[i] = !valid ? 0
                      : static_cast<std::uint16_t>(mm ? std::lround(d * 1000.f) : a / d + b);
  }
  std::vector<std::uint8_t> stream;
  if (codec == "rvl") {
    const auto w = static_cast<std::uint32_t>(depth.width),
               h = static_cast<std::uint32_t>(depth.height);
    stream.resize(8);
    std::memcpy(stream.data(), &w, 4);
    std::memcpy(stream.data() + 4, &h, 4);
    const std::vector<std::uint8_t> rvl = rvlOf(codes);
    stream.insert(stream.end(), rvl.begin(), rvl.end());
  } else {
    const cv::Mat image(depth.height, depth.width, CV_16UC1, codes.data());
    cv::imencode(".png", image, stream);
  }
  sensor_msgs::CompressedImage msg;
  msg.format = encoding + "; compressedDepth " + codec;
  const std::int32_t format_code = 0;  // the plugin's INV_DEPTH, for either encoding
  const float params[2] = {mm ? 0.f : a, mm ? 0.f : b};
  msg.data.resize(12);
  std::memcpy(msg.data.data(), &format_code, 4);
  std::memcpy(msg.data.data() + 4, params, 8);
  msg.data.insert(msg.data.end(), stream.begin(), stream.end());
  return msg;
}

}  // namespace upd::test
