// GzOutputStream: the data written comes back byte for byte through MRPT's CFileGZInputStream
// (what rawlog readers use) and through gzip, in members of any size, batch after batch; an empty
// stream is a valid gzip file; a path that cannot be written is named.
#include "upd/mrpt_bridge/gz_output_stream.h"

#include <gtest/gtest.h>
#include <mrpt/io/CFileGZInputStream.h>

#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "temp_dir.h"

namespace {

using upd::mrpt_bridge::GzOutputStream;

std::vector<char> readBack(const std::string& path) {
  mrpt::io::CFileGZInputStream in(path);
  std::vector<char> all;
  char buf[4096];
  for (std::size_t n; (n = in.Read(buf, sizeof buf)) > 0;) all.insert(all.end(), buf, buf + n);
  return all;
}

// Bytes that compress as sensor data does: runs and noise.
std::vector<char> someData(std::size_t n) {
  std::mt19937 rng(7);
  std::vector<char> data(n);
  for (std::size_t i = 0; i < n; ++i) data[i] = static_cast<char>(i % 97 < 60 ? i / 97 : rng());
  return data;
}

TEST(GzOutputStream, WritesWhatGzipReadersReadBack) {
  const upd::test::TempDir dir("gz_stream");
  for (const std::size_t member_bytes : {std::size_t{1000}, std::size_t{1} << 20}) {
    const std::string path = dir.file("data-" + std::to_string(member_bytes) + ".gz");
    const std::vector<char> data = someData(250'000);
    GzOutputStream out(path, 1, member_bytes);
    for (std::size_t at = 0, piece = 1; at < data.size();
         at += piece, piece = piece * 3 % 1999 + 1) {
      piece = std::min(piece, data.size() - at);
      ASSERT_EQ(out.Write(data.data() + at, piece), piece);
    }
    EXPECT_EQ(out.getTotalBytesCount(), data.size());
    out.close();
    EXPECT_EQ(readBack(path), data) << "members of " << member_bytes << " bytes";
    EXPECT_EQ(std::system(("gzip -t " + path).c_str()), 0) << path;
  }
}

TEST(GzOutputStream, EmptyStreamIsAValidGzipFile) {
  const upd::test::TempDir dir("gz_stream");
  const std::string path = dir.file("empty.gz");
  GzOutputStream out(path);
  out.close();
  EXPECT_TRUE(readBack(path).empty());
  EXPECT_EQ(std::system(("gzip -t " + path).c_str()), 0);
}

TEST(GzOutputStream, PathThatCannotBeWrittenIsNamed) {
  try {
    GzOutputStream out("/nonexistent-dir/x.rawlog");
    FAIL() << "opened";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot write /nonexistent-dir/x.rawlog");
  }
}

}  // namespace
