// Where the tests find the shared real sensor data, and a visible skip when it is absent.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace upd::test {

inline std::filesystem::path sharedDataDir() {
  if (const char* env = std::getenv("UPD_SHARED_DATA_DIR")) return env;
#ifdef UPD_SHARED_DATA_DIR
  return UPD_SHARED_DATA_DIR;
#else
  return "../shared/data";
#endif
}

/// Path of a file under the shared data directory, or "" when it is missing.
inline std::string sharedFile(const std::string& rel) {
  const auto p = sharedDataDir() / rel;
  return std::filesystem::exists(p) ? p.string() : std::string();
}

}  // namespace upd::test

/// Skips the current test with a visible message when a shared data file is absent.
#define UPD_REQUIRE_SHARED_FILE(var, rel)                                                   \
  const std::string var = ::upd::test::sharedFile(rel);                                    \
  if (var.empty()) {                                                                       \
    GTEST_SKIP() << "shared data file " << (rel) << " not found under "                    \
                 << ::upd::test::sharedDataDir() << " (set UPD_SHARED_DATA_DIR); skipped"; \
  }
