// depthFromCompressedDepth: image_transport's compressedDepth plugin read back (its
// compression_common.h and codec.cpp fix the layout: a 12-byte ConfigHeader, then the PNG or
// RVL stream of 16-bit codes). The PNG is decoded by upd::io's libpng reader, the RVL stream
// (Wilson's run-length variable-length code) here, every read and write bounded: the plugin's
// own decoder trusts the stream's counts.
#include "upd/io/png_gray16.h"
#include "upd/ros1/conversions.h"

#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace upd::ros1 {

namespace {

constexpr std::size_t kHeaderBytes = 12;  // int32 format code, float depthParam[2]
constexpr std::uint32_t kMaxSide = 1u << 15;

[[noreturn]] void fail(const sensor_msgs::CompressedImage& m, const std::string& why) {
  throw MessageError("compressed depth image (format '" + m.format + "'): " + why);
}

// The codec the format names: "png" or "rvl" ("" where it names none the plugin writes).
std::string codecOf(const std::string& format) {
  const std::size_t semicolon = format.find(';');
  if (semicolon == std::string::npos) return "png";  // the plugin's oldest format
  const std::string rest = format.substr(semicolon);
  if (rest.find("compressedDepth png") != std::string::npos) return "png";
  if (rest.find("compressedDepth rvl") != std::string::npos) return "rvl";
  const bool bare = rest.find("compressedDepth") != std::string::npos &&
                    rest.find("compressedDepth ") == std::string::npos;
  return bare ? "png" : "";
}

// The reader of an RVL stream: 32-bit little-endian words of eight 4-bit nibbles, the highest
// first; a value is a run of nibbles of 3 bits each, the 4th bit set on all but its last.
class RvlReader {
 public:
  RvlReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  // The next value, or false where the stream ends first or a value runs past 32 bits.
  bool next(std::uint32_t& value) {
    value = 0;
    for (int shift = 0; shift < 33; shift += 3) {
      if (nibbles_ == 0) {
        if (at_ + 4 > size_) return false;
        std::memcpy(&word_, data_ + at_, 4);
        at_ += 4;
        nibbles_ = 8;
      }
      const std::uint32_t nibble = word_ >> 28;
      word_ <<= 4;
      --nibbles_;
      value |= (nibble & 7u) << shift;
      if ((nibble & 8u) == 0) return true;
    }
    return false;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_, at_ = 0;
  std::uint32_t word_ = 0;
  int nibbles_ = 0;
};

// The RVL stream's codes into codes (width x height of its first 8 bytes).
void decodeRvl(const sensor_msgs::CompressedImage& m, const std::uint8_t* data, std::size_t size,
               std::uint32_t& width, std::uint32_t& height, std::vector<std::uint16_t>& codes) {
  if (size < 8) fail(m, "its RVL stream holds no size");
  std::memcpy(&width, data, 4);
  std::memcpy(&height, data + 4, 4);
  const std::uint64_t pixels = std::uint64_t{width} * height;
  if (width == 0 || height == 0 || width > kMaxSide || height > kMaxSide ||
      pixels > kMaxCompressedDepthPixels) {
    fail(m, "RVL size " + std::to_string(width) + " x " + std::to_string(height) +
                ": a depth image has 1 to " + std::to_string(kMaxSide) + " pixels a side");
  }
  codes.assign(pixels, 0);
  RvlReader in(data + 8, size - 8);
  std::uint64_t at = 0;
  std::uint16_t previous = 0;
  while (at < pixels) {
    std::uint32_t zeros = 0, nonzeros = 0;
    if (!in.next(zeros) || zeros > pixels - at) fail(m, "its RVL stream is damaged or cut short");
    at += zeros;  // (codes are 0 already)
    if (!in.next(nonzeros) || nonzeros > pixels - at) {
      fail(m, "its RVL stream is damaged or cut short");
    }
    for (std::uint32_t i = 0; i < nonzeros; ++i) {
      std::uint32_t zigzag = 0;
      if (!in.next(zigzag)) fail(m, "its RVL stream is damaged or cut short");
      const auto delta = static_cast<std::int32_t>((zigzag >> 1) ^ (0u - (zigzag & 1u)));
      previous = static_cast<std::uint16_t>(previous + delta);
      codes[at++] = previous;
    }
  }
}

// The PNG's codes into codes.
void decodePng(const sensor_msgs::CompressedImage& m, const std::uint8_t* data, std::size_t size,
               std::uint32_t& width, std::uint32_t& height, std::vector<std::uint16_t>& codes) {
  io::Gray16 png = io::decodeGray16(data, size, kMaxSide, kMaxCompressedDepthPixels);
  const std::string why = io::whyNotGray16(png, kMaxSide, kMaxCompressedDepthPixels);
  if (!why.empty()) fail(m, "the data after its 12-byte header: " + why);
  width = png.width;
  height = png.height;
  codes = std::move(png.pixels);
}

}  // namespace

core::DepthImage depthFromCompressedDepth(const sensor_msgs::CompressedImage& image) {
  namespace enc = sensor_msgs::image_encodings;
  const std::string encoding = image.format.substr(0, image.format.find(';'));
  const bool mm = encoding == enc::TYPE_16UC1 || encoding == enc::MONO16;
  const bool inverse = encoding == enc::TYPE_32FC1;
  const std::string codec = codecOf(image.format);
  if (codec.empty() || (!mm && !inverse)) {
    fail(image, "expected '16UC1; compressedDepth png' or 'rvl', or the same with 32FC1");
  }
  if (image.data.size() <= kHeaderBytes) {
    fail(image, std::to_string(image.data.size()) +
                    " bytes of data: the 12-byte header and a stream after it are needed");
  }
  float p[2];
  std::memcpy(p, image.data.data() + 4, sizeof p);
  if (inverse && !(std::isfinite(p[0]) && std::isfinite(p[1]))) {
    fail(image, "its inverse-depth parameters are not finite");
  }
  const std::uint8_t* stream = image.data.data() + kHeaderBytes;
  const std::size_t size = image.data.size() - kHeaderBytes;
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint16_t> codes;
  if (codec == "rvl") {
    decodeRvl(image, stream, size, width, height, codes);
  } else {
    decodePng(image, stream, size, width, height, codes);
  }
  core::DepthImage depth;
  depth.width = static_cast<int>(width);
  depth.height = static_cast<int>(height);
  depth.depth_m.resize(codes.size());
  for (std::size_t i = 0; i < codes.size(); ++i) {
    // (The plugin's arithmetic, in float: 0.001 m a code, or p0 / (code - p1).)
    const float d = mm ? codes[i] * 0.001f
                       : (codes[i] == 0 ? 0.f : p[0] / (static_cast<float>(codes[i]) - p[1]));
    depth.depth_m[i] = std::isfinite(d) && d > 0 ? d : 0.f;
  }
  return depth;
}

}  // namespace upd::ros1
