#include "upd/io/whole_file.h"

#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace upd::io {

std::string readWholeFile(const std::string& path, std::uintmax_t max_bytes) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw std::runtime_error("not found");
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw std::runtime_error("unreadable");
  if (size > max_bytes) throw std::runtime_error("larger than " + std::to_string(max_bytes) + " bytes");
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.is_open() || in.bad()) throw std::runtime_error("unreadable");
  return bytes;
}

}  // namespace upd::io
