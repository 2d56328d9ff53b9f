// Helpers shared by the upd_io sources (not installed): uniform error messages and
// byte-order-explicit binary encoding, so every format reports and encodes the same way.
#pragma once

#include <cstdint>
#include <cstring>
#include <istream>
#include <stdexcept>
#include <string>

namespace upd::io::detail {

/// "<path>: <what>" as a std::runtime_error: every reader's error names the file first.
inline std::runtime_error fileError(const std::string& path, const std::string& what) {
  return std::runtime_error("'" + path + "': " + what);
}

/// Throws fileError unless path names an existing regular file.
void requireReadableFile(const std::string& path);

/// The bytes from the stream's position to its end, the position kept (0 when the stream cannot
/// tell): what a header's count is checked against before anything is allocated for it.
std::uint64_t bytesLeft(std::istream& in);

/// What the first bytes of a file (head) say it is: "a PLY file", "a PCD file",
/// "gzip-compressed data", "text", or "" when none of these (binary data of no known kind).
std::string sniffFormat(const std::string& head);

constexpr bool kHostIsLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

inline void reverseBytes(unsigned char* p, std::size_t n) {
  for (std::size_t i = 0; i < n / 2; ++i) {
    const unsigned char t = p[i];
    p[i] = p[n - 1 - i];
    p[n - 1 - i] = t;
  }
}

/// Appends v to out in little-endian byte order (the order of every binary file we write).
template <class T>
void appendLittleEndian(std::string& out, T v) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &v, sizeof(T));
  if (!kHostIsLittleEndian) reverseBytes(bytes, sizeof(T));
  out.append(reinterpret_cast<const char*>(bytes), sizeof(T));
}

}  // namespace upd::io::detail
