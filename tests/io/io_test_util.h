// Shared helpers of the io tests: a per-test temporary directory (temp_dir.h) and whole-file
// reads.
#pragma once

#include <gtest/gtest.h>

#include "temp_dir.h"

#include <fstream>
#include <sstream>
#include <string>

namespace upd::test {

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

}  // namespace upd::test
