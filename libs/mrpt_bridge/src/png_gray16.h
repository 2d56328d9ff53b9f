// Private to libs/mrpt_bridge: a 16-bit single-channel PNG decoded by libpng from memory, its
// errors returned as text (libpng's own handler would print them on stderr).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace upd::mrpt_bridge::detail {

/// What decodeGray16 found.
struct Gray16 {
  std::uint32_t width = 0, height = 0;
  std::vector<std::uint16_t> pixels;  ///< row by row, in the host's byte order
  int bit_depth = 0, channels = 0;    ///< of the file, whatever it holds
  std::string error;                  ///< empty where it decoded a 16-bit single-channel image
};

/// Decodes the PNG bytes[0, n): a 16-bit grey image into pixels; another kind of image leaves
/// pixels empty with its bit depth and channels (error empty); a damaged file sets error to
/// libpng's reason ("IHDR: CRC error", "file cut short"). At most max_side pixels a side and
/// max_pixels in all (larger: an error before any allocation for them).
Gray16 decodeGray16(const unsigned char* bytes, std::size_t n, std::uint32_t max_side,
                    std::uint64_t max_pixels);

}  // namespace upd::mrpt_bridge::detail
