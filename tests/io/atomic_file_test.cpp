// Atomic output: the target is replaced whole or not at all, and no temporary file is left.
#include "io_test_util.h"
#include "upd/io/atomic_file.h"
#include "upd/io/cloud_io.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <ostream>
#include <sstream>
#include <string>

namespace core = upd::core;

namespace {

namespace fs = std::filesystem;

using upd::test::TempDir;

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

std::size_t filesIn(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    (void)e;
    ++n;
  }
  return n;
}

TEST(AtomicFile, WritesAndReplaces) {
  TempDir dir;
  const std::string f = dir.file("out.txt");
  upd::io::writeFileAtomically(f, [](std::ostream& os) { os << "first"; });
  EXPECT_EQ(readText(f), "first");
  upd::io::writeFileAtomically(f, [](std::ostream& os) { os << "second\0binary" << '\0'; });
  EXPECT_EQ(readText(f), std::string("second\0", 7));
  EXPECT_EQ(filesIn(dir.path()), 1u);
}

TEST(AtomicFile, ThrowingWriterLeavesTargetIntactAndNoTemporary) {
  TempDir dir;
  const std::string f = dir.file("keep.txt");
  upd::io::writeFileAtomically(f, [](std::ostream& os) { os << "precious"; });
  struct WriterFailure {};
  EXPECT_THROW(upd::io::writeFileAtomically(f,
                                            [](std::ostream& os) {
                                              os << "half of the new con";
                                              throw WriterFailure{};
                                            }),
               WriterFailure);
  EXPECT_EQ(readText(f), "precious");
  EXPECT_EQ(filesIn(dir.path()), 1u) << "a temporary file was left behind";

  // Same when there was no previous file: nothing appears.
  const std::string g = dir.file("never.txt");
  EXPECT_THROW(upd::io::writeFileAtomically(g, [](std::ostream&) { throw WriterFailure{}; }),
               WriterFailure);
  EXPECT_FALSE(fs::exists(g));
  EXPECT_EQ(filesIn(dir.path()), 1u);
}

// Writers that open the file by name (MRPT's gzip streams, GDAL) get a temporary path with the
// suffix they asked for; what they leave is renamed into place, a throw leaves nothing.
TEST(AtomicFile, WriterByNameGetsATemporaryPathWithItsSuffix) {
  TempDir dir;
  const std::string f = dir.file("map.tif");
  std::string seen;
  upd::io::writeFileAtomicallyVia(
      f,
      [&](const std::string& tmp) {
        seen = tmp;
        std::ofstream(tmp) << "tiff";
      },
      ".tif");
  EXPECT_NE(seen, f);
  EXPECT_EQ(fs::path(seen).parent_path(), fs::path(f).parent_path());
  EXPECT_EQ(fs::path(seen).extension(), ".tif");
  EXPECT_EQ(readText(f), "tiff");
  struct WriterFailure {};
  EXPECT_THROW(upd::io::writeFileAtomicallyVia(f,
                                               [](const std::string& tmp) {
                                                 std::ofstream(tmp) << "half";
                                                 throw WriterFailure{};
                                               }),
               WriterFailure);
  EXPECT_EQ(readText(f), "tiff");
  EXPECT_EQ(filesIn(dir.path()), 1u) << "a temporary file was left behind";
  try {
    upd::io::writeFileAtomicallyVia(dir.file("none.rawlog"), [](const std::string&) {});
    FAIL() << "a writer that writes nothing must be an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("none.rawlog"), std::string::npos) << e.what();
  }
  EXPECT_THROW(upd::io::writeFileAtomicallyVia(dir.file("no/such/dir.bin"), [](const std::string&) {}),
               std::runtime_error);
}

TEST(AtomicFile, StreamFailureIsAnErrorNamingTheFile) {
  // What a full disk looks like to the writer: the stream goes bad.
  TempDir dir;
  const std::string f = dir.file("full.bin");
  upd::io::writeFileAtomically(f, [](std::ostream& os) { os << "old"; });
  try {
    upd::io::writeFileAtomically(f, [](std::ostream& os) {
      os << "new";
      os.setstate(std::ios::badbit);
    });
    ADD_FAILURE() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(f), std::string::npos) << e.what();
  }
  EXPECT_EQ(readText(f), "old");
  EXPECT_EQ(filesIn(dir.path()), 1u);
}

TEST(AtomicFile, MissingDirectoryIsNamed) {
  TempDir dir;
  const std::string missing = dir.file("no/such/dir");
  const std::string f = missing + "/out.ply";
  for (int k = 0; k < 2; ++k) {
    try {
      if (k == 0) {
        upd::io::writeFileAtomically(f, [](std::ostream& os) { os << "x"; });
      } else {
        upd::core::PointCloud c;
        c.push_back(1, 2, 3);
        upd::io::writePly(f, c);
      }
      ADD_FAILURE() << "no exception";
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("'" + missing + "'"), std::string::npos) << msg;
      EXPECT_NE(msg.find("does not exist"), std::string::npos) << msg;
    }
  }
  EXPECT_FALSE(fs::exists(dir.file("no")));
}

TEST(AtomicFile, TargetThatIsADirectoryFails) {
  TempDir dir;
  const std::string d = dir.file("sub");
  fs::create_directory(d);
  EXPECT_THROW(upd::io::writeFileAtomically(d, [](std::ostream& os) { os << "x"; }),
               std::runtime_error);
  EXPECT_TRUE(fs::is_directory(d));
  EXPECT_EQ(filesIn(dir.path()), 1u);
}

TEST(AtomicFile, RelativePathInCurrentDirectory) {
  TempDir dir;
  const fs::path old = fs::current_path();
  fs::current_path(dir.file(""));
  upd::io::writeFileAtomically("plain.txt", [](std::ostream& os) { os << "here"; });
  fs::current_path(old);
  EXPECT_EQ(readText(dir.file("plain.txt")), "here");
}

}  // namespace
