// KITTI .bin scans and SemanticKITTI .label files: fixed-size little-endian records.
#include "upd/io/kitti_bin.h"

#include "upd/io/atomic_file.h"

#include "io_detail.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <ostream>

namespace upd::io {

namespace {

using detail::fileError;

constexpr std::size_t kRecordBytes = 16;  // float32 x, y, z, intensity

// The whole file, after checking it is a regular file and not another format.
std::string readAll(const std::string& path, const char* what) {
  detail::requireReadableFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw fileError(path, "cannot open for reading");
  std::string bytes(static_cast<std::size_t>(std::filesystem::file_size(path)), '\0');
  if (!in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()))) {
    throw fileError(path, "read error");
  }
  const std::string other = detail::sniffFormat(bytes.substr(0, 256));
  if (!other.empty()) throw fileError(path, "is " + other + ", not " + what);
  return bytes;
}

template <class T>
T loadLittleEndian(const char* p) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, p, sizeof(T));
  if (!detail::kHostIsLittleEndian) detail::reverseBytes(b, sizeof(T));
  T v;
  std::memcpy(&v, b, sizeof(T));
  return v;
}

}  // namespace

KittiScan readKittiBin(const std::string& path) {
  const std::string bytes =
      readAll(path, "a KITTI .bin scan (float32 x y z intensity per point)");
  if (bytes.size() % kRecordBytes != 0) {
    throw fileError(path, "truncated or not a KITTI .bin scan: " + std::to_string(bytes.size()) +
                              " bytes is not a whole number of 16-byte points (float32 x y z "
                              "intensity); the last point has " +
                              std::to_string(bytes.size() % kRecordBytes) + " bytes");
  }
  const std::size_t n = bytes.size() / kRecordBytes;
  KittiScan scan;
  scan.cloud.reserve(n);
  scan.intensity.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const char* p = bytes.data() + i * kRecordBytes;
    scan.cloud.push_back(loadLittleEndian<float>(p), loadLittleEndian<float>(p + 4),
                         loadLittleEndian<float>(p + 8));
    scan.intensity.push_back(loadLittleEndian<float>(p + 12));
  }
  scan.cloud.width = n;
  scan.cloud.height = 1;
  return scan;
}

void writeKittiBin(const std::string& path, const core::PointCloud& cloud,
                   const std::vector<float>& intensity) {
  const std::size_t n = cloud.size();
  if (cloud.y.size() != n || cloud.z.size() != n) {
    throw std::invalid_argument("writeKittiBin: x, y, z of the cloud differ in size");
  }
  if (!intensity.empty() && intensity.size() != n) {
    throw std::invalid_argument("writeKittiBin: " + std::to_string(intensity.size()) +
                                " intensities for " + std::to_string(n) + " points");
  }
  std::string body;
  body.reserve(n * kRecordBytes);
  for (std::size_t i = 0; i < n; ++i) {
    detail::appendLittleEndian(body, cloud.x[i]);
    detail::appendLittleEndian(body, cloud.y[i]);
    detail::appendLittleEndian(body, cloud.z[i]);
    detail::appendLittleEndian(body, intensity.empty() ? 0.f : intensity[i]);
  }
  writeFileAtomically(path, [&](std::ostream& os) {
    os.write(body.data(), static_cast<std::streamsize>(body.size()));
  });
}

std::vector<std::uint32_t> readSemanticKittiLabels(const std::string& path, std::size_t points) {
  const std::string bytes = readAll(path, "a SemanticKITTI .label file (uint32 per point)");
  if (bytes.size() % 4 != 0) {
    throw fileError(path, "truncated SemanticKITTI .label file: " + std::to_string(bytes.size()) +
                              " bytes is not a whole number of uint32 labels");
  }
  const std::size_t n = bytes.size() / 4;
  if (points != 0 && n != points) {
    throw fileError(path, std::to_string(n) + " labels for a scan of " + std::to_string(points) +
                              " points");
  }
  std::vector<std::uint32_t> labels(n);
  for (std::size_t i = 0; i < n; ++i) labels[i] = loadLittleEndian<std::uint32_t>(bytes.data() + 4 * i);
  return labels;
}

}  // namespace upd::io
