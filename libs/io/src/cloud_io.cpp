// Format dispatch by extension, and the checks every reader shares (a file of another format
// under a cloud extension is named as what it is).
#include "upd/io/cloud_io.h"

#include "upd/io/kitti_bin.h"

#include "io_detail.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
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

std::string sniffFormat(const std::string& head) {
  if (head.empty()) return "";
  if (head.rfind("ply\n", 0) == 0 || head.rfind("ply\r", 0) == 0) return "a PLY file";
  if (head.rfind("\x1f\x8b", 0) == 0) return "gzip-compressed data";
  // A PCD header: "# .PCD v0.7 ..." comment lines, then VERSION or FIELDS.
  std::size_t line = 0;
  while (line < head.size() && head[line] == '#') {
    if (head.compare(line, 6, "# .PCD") == 0) return "a PCD file";
    const std::size_t nl = head.find('\n', line);
    if (nl == std::string::npos) break;
    line = nl + 1;
  }
  if (head.compare(line, 8, "VERSION ") == 0 || head.compare(line, 7, "FIELDS ") == 0) {
    return "a PCD file";
  }
  const bool text = std::all_of(head.begin(), head.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return (u >= 0x20 && u < 0x7f) || u == '\n' || u == '\r' || u == '\t';
  });
  return text ? "text" : "";
}

namespace {

// The first bytes of path (up to 256).
std::string headOf(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string head(256, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return head;
}

// A PCD, PLY or gzip file under another cloud extension is named as what it is.
void requireContentMatchesExtension(const std::string& path, const std::string& ext) {
  const std::string kind = sniffFormat(headOf(path));
  const std::string kind_ext = kind == "a PLY file" ? ".ply" : kind == "a PCD file" ? ".pcd" : "";
  if (!kind_ext.empty() && kind_ext != ext) {
    throw fileError(path, "is " + kind + ", not " + ext + " (rename it to " + kind_ext + ")");
  }
  if (kind == "gzip-compressed data") {
    throw fileError(path, "is gzip-compressed data, not a " + ext + " point cloud (decompress it)");
  }
}

}  // namespace

std::uint64_t bytesLeft(std::istream& in) {
  const std::streamoff start = in.tellg();
  in.seekg(0, std::ios::end);
  const std::streamoff end = in.tellg();
  in.seekg(start);
  return start < 0 || end < start ? 0 : static_cast<std::uint64_t>(end - start);
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
  const bool known = ext == ".pcd" || ext == ".ply" || ext == ".xyz" || ext == ".txt" ||
                     ext == ".bin";
  if (!known) {
    throw detail::fileError(path, "unsupported point cloud extension '" + ext +
                                      "' (supported: .pcd, .ply, .xyz, .txt, .bin (KITTI))");
  }
  detail::requireReadableFile(path);
  detail::requireContentMatchesExtension(path, ext);
  if (ext == ".pcd") return readPcd(path);
  if (ext == ".ply") return readPly(path);
  if (ext == ".bin") return readKittiBin(path).cloud;
  return readXyz(path);
}

}  // namespace upd::io
