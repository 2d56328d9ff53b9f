// Format dispatch by extension, and the checks every reader shares.
#include "upd/io/cloud_io.h"

#include "io_detail.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <system_error>

namespace upd::io {

namespace detail {

void requireReadableFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (!fs::exists(st)) throw fileError(path, "file not found");
  if (fs::is_directory(st)) throw fileError(path, "is a directory, not a point cloud file");
  if (!fs::is_regular_file(st)) throw fileError(path, "is not a regular file");
}

}  // namespace detail

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

core::PointCloud readCloud(const std::string& path) {
  const std::string ext = lowerExtension(path);
  if (ext == ".pcd") return readPcd(path);
  if (ext == ".ply") return readPly(path);
  if (ext == ".xyz" || ext == ".txt") return readXyz(path);
  throw detail::fileError(path, "unsupported point cloud extension '" + ext +
                                    "' (supported: .pcd, .ply, .xyz, .txt)");
}

}  // namespace upd::io
