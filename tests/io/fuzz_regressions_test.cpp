// Inputs that once crashed, hung or were misread by a reader (found by the fuzzers of
// tests/fuzz or the bad-input catalogue), kept in tests/io/regressions/: each must now be
// refused with a message naming the file, or read, as its name's suffix says (`*.ok.<ext>` are
// read, every other file is refused). None may crash.
#include "upd/io/cloud_io.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

namespace {

namespace fs = std::filesystem;

TEST(ReaderRegressions, EveryKeptInputIsRefusedOrReadWithoutCrashing) {
  const fs::path dir = fs::path(UPD_SOURCE_DIR) / "tests" / "io" / "regressions";
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string path = e.path().string();
    const std::string ext = upd::io::lowerExtension(path);
    if (ext != ".pcd" && ext != ".ply" && ext != ".xyz" && ext != ".bin") continue;
    ++n;
    const bool should_read = e.path().stem().extension() == ".ok";
    try {
      const upd::core::PointCloud c = upd::io::readCloud(path);
      EXPECT_TRUE(should_read) << path << " was read (" << c.size() << " points)";
    } catch (const std::runtime_error& err) {
      EXPECT_FALSE(should_read) << path << ": " << err.what();
      EXPECT_NE(std::string(err.what()).find(path), std::string::npos) << err.what();
    }
  }
  EXPECT_GT(n, 0u) << "no inputs in " << dir;
}

}  // namespace
