#include "upd/io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace upd::io {

namespace fs = std::filesystem;

namespace {

std::string randomSuffix() {
  // Seeded once per process from the OS: the pid already separates processes, the random part
  // separates concurrent writers of the same target within one process.
  static thread_local std::mt19937_64 rng{std::random_device{}()};
  std::ostringstream os;
  os << std::hex << rng();
  return os.str();
}

fs::path temporaryPathFor(const fs::path& target) {
  fs::path tmp = target;
  tmp += ".tmp-" + std::to_string(::getpid()) + "-" + randomSuffix();
  return tmp;
}

void removeQuietly(const fs::path& p) {
  std::error_code ec;
  fs::remove(p, ec);  // best effort: we are already reporting a more relevant error
}

void checkTarget(const std::string& path) {
  if (path.empty()) throw std::runtime_error("cannot write a file with an empty name");
  const fs::path target(path);
  const fs::path dir = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw std::runtime_error("cannot write '" + path + "': output directory '" + dir.string() +
                             "' does not exist");
  }
  if (fs::is_directory(target, ec)) {
    throw std::runtime_error("cannot write '" + path + "': it is a directory");
  }
}

void renameIntoPlace(const fs::path& tmp, const std::string& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    removeQuietly(tmp);
    throw std::runtime_error("cannot write '" + path + "': renaming the temporary file failed: " +
                             ec.message());
  }
}

}  // namespace

void writeFileAtomically(const std::string& path,
                         const std::function<void(std::ostream&)>& write) {
  checkTarget(path);
  const fs::path tmp = temporaryPathFor(fs::path(path));
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) {
    const int err = errno;
    throw std::runtime_error("cannot write '" + path + "': cannot create temporary file '" +
                             tmp.string() + "': " + std::strerror(err));
  }

  try {
    write(out);
    out.flush();
    if (!out) {
      throw std::runtime_error("error while writing '" + path +
                               "' (disk full or I/O error); the previous file is unchanged");
    }
    out.close();
    if (out.fail()) {
      throw std::runtime_error("error while closing '" + path +
                               "' (disk full or I/O error); the previous file is unchanged");
    }
  } catch (...) {
    if (out.is_open()) out.close();
    removeQuietly(tmp);
    throw;
  }
  renameIntoPlace(tmp, path);
}

void writeFileAtomicallyVia(const std::string& path,
                            const std::function<void(const std::string& tmp_path)>& write,
                            const std::string& suffix) {
  checkTarget(path);
  fs::path tmp = temporaryPathFor(fs::path(path));
  tmp += suffix;
  try {
    write(tmp.string());
  } catch (...) {
    removeQuietly(tmp);
    throw;
  }
  if (!fs::exists(tmp)) {
    throw std::runtime_error("cannot write '" + path + "': nothing was written");
  }
  renameIntoPlace(tmp, path);
}

}  // namespace upd::io
