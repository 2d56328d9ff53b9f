// Small point cloud files of every format the readers take, built byte by byte (no reader or
// writer of ours involved): the bad-input catalogue damages them, and the fuzzers start from
// them. Header-only; every function returns the file's bytes.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace upd::test::samples {

struct Xyz {
  float x, y, z;
};

/// n x n points on a gentle slope, 5 cm apart (something the UPD can score).
inline std::vector<Xyz> grid(int n = 6) {
  std::vector<Xyz> p;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) p.push_back({0.05f * i, 0.05f * j, 0.01f * i});
  }
  return p;
}

template <class T>
void putLe(std::string& out, T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(reinterpret_cast<const char*>(b), sizeof(T));  // the test hosts are little-endian
}

template <class T>
void putBe(std::string& out, T v) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (std::size_t i = sizeof(T); i-- > 0;) out.push_back(static_cast<char>(b[i]));
}

inline std::string pcdHeader(std::size_t n, const char* data) {
  return "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
         "TYPE F F F\nCOUNT 1 1 1\nWIDTH " + std::to_string(n) + "\nHEIGHT 1\n"
         "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(n) + "\nDATA " + data + "\n";
}

inline std::string pcdAscii(const std::vector<Xyz>& p) {
  std::string s = pcdHeader(p.size(), "ascii");
  for (const Xyz& q : p) {
    s += std::to_string(q.x) + " " + std::to_string(q.y) + " " + std::to_string(q.z) + "\n";
  }
  return s;
}

inline std::string pcdBinary(const std::vector<Xyz>& p) {
  std::string s = pcdHeader(p.size(), "binary");
  for (const Xyz& q : p) {
    putLe(s, q.x);
    putLe(s, q.y);
    putLe(s, q.z);
  }
  return s;
}

/// binary_compressed: sizes (compressed, uncompressed), then the fields one after the other
/// (all x, all y, all z) as LZF literal runs of up to 32 bytes (control byte = length - 1).
inline std::string pcdBinaryCompressed(const std::vector<Xyz>& p) {
  std::string raw;
  for (int f = 0; f < 3; ++f) {
    for (const Xyz& q : p) putLe(raw, f == 0 ? q.x : f == 1 ? q.y : q.z);
  }
  std::string lzf;
  for (std::size_t i = 0; i < raw.size(); i += 32) {
    const std::size_t len = std::min<std::size_t>(32, raw.size() - i);
    lzf.push_back(static_cast<char>(len - 1));
    lzf.append(raw, i, len);
  }
  std::string s = pcdHeader(p.size(), "binary_compressed");
  putLe(s, static_cast<std::uint32_t>(lzf.size()));
  putLe(s, static_cast<std::uint32_t>(raw.size()));
  return s + lzf;
}

inline std::string plyHeader(std::size_t n, const char* format) {
  return std::string("ply\nformat ") + format + " 1.0\ncomment sample\nelement vertex " +
         std::to_string(n) + "\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
}

inline std::string plyAscii(const std::vector<Xyz>& p) {
  std::string s = plyHeader(p.size(), "ascii");
  for (const Xyz& q : p) {
    s += std::to_string(q.x) + " " + std::to_string(q.y) + " " + std::to_string(q.z) + "\n";
  }
  return s + "3 0 1 2\n";
}

inline std::string plyBinary(const std::vector<Xyz>& p, bool big_endian) {
  std::string s = plyHeader(p.size(), big_endian ? "binary_big_endian" : "binary_little_endian");
  auto put = [&](auto v) { big_endian ? putBe(s, v) : putLe(s, v); };
  for (const Xyz& q : p) {
    put(q.x);
    put(q.y);
    put(q.z);
  }
  s.push_back(3);
  for (std::int32_t i = 0; i < 3; ++i) put(i);
  return s;
}

inline std::string xyzText(const std::vector<Xyz>& p) {
  std::string s = "# x y z\n";
  for (const Xyz& q : p) {
    s += std::to_string(q.x) + " " + std::to_string(q.y) + " " + std::to_string(q.z) + "\n";
  }
  return s;
}

/// KITTI velodyne .bin: float32 x y z intensity per point.
inline std::string kittiBin(const std::vector<Xyz>& p) {
  std::string s;
  for (const Xyz& q : p) {
    putLe(s, q.x);
    putLe(s, q.y);
    putLe(s, q.z);
    putLe(s, 0.5f);
  }
  return s;
}

}  // namespace upd::test::samples
