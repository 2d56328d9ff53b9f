// The fuzzers' input as a file: the readers take a path, so each input is written to one file
// per process (in /dev/shm when there is one) with the extension that picks the reader.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace upd::fuzz {

inline std::string inputPath(const std::string& ext) {
  const std::filesystem::path dir =
      std::filesystem::exists("/dev/shm") ? "/dev/shm" : std::filesystem::temp_directory_path();
  return (dir / ("upd_fuzz_" + std::to_string(::getpid()) + ext)).string();
}

/// Writes the input to path (replacing the last one).
inline void writeInput(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

}  // namespace upd::fuzz
