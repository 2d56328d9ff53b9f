// A 16-bit single-channel PNG decoded by libpng from memory, its errors returned as text
// (libpng's own handler would print them on stderr; OpenCV's decoder lets it), the header's size
// checked before anything is allocated: the depth PNG files (mrpt_bridge's readDepthPng) and the
// compressed depth images of ROS (ros1's depthFromCompressedDepth).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace upd::io {

/// What decodeGray16 found.
struct Gray16 {
  enum class Status {
    Gray16,     ///< decoded into pixels
    NotPng,     ///< no PNG signature and IHDR (text, another format, empty)
    TooLarge,   ///< width x height by the header 0 or beyond the limits (nothing allocated)
    Damaged,    ///< libpng's reason in error (a chunk's CRC, its data, the file cut short)
    NotGray16,  ///< a PNG of another kind: bit_depth and channels say which
  };
  Status status = Status::NotPng;
  std::uint32_t width = 0, height = 0;  ///< by the header
  std::vector<std::uint16_t> pixels;    ///< row by row, in the host's byte order
  int bit_depth = 0, channels = 0;      ///< of the file, whatever it holds
  std::string error;                    ///< Damaged: libpng's reason
};

/// Decodes the PNG bytes[0, n) where it is a 16-bit grey image of at most max_side pixels a
/// side and max_pixels in all; else says why not (Gray16::Status).
Gray16 decodeGray16(const unsigned char* bytes, std::size_t n, std::uint32_t max_side,
                    std::uint64_t max_pixels);

/// Why g (decodeGray16's answer with those limits) is no depth image, as the end of a one-line
/// error ("not a PNG image", "damaged PNG (...)", ...); "" where it decoded.
std::string whyNotGray16(const Gray16& g, std::uint32_t max_side, std::uint64_t max_pixels);

}  // namespace upd::io
