// The scored cloud of `upd analyze` as users open it. By default it holds the valid points
// only, so no viewer sees the frame's invalid (NaN) pixels as a cluster at the origin, and
// CloudCompare (Debian's cloudcompare) loads its scalar fields in command-line mode;
// `--organized` keeps every pixel with the image's width and height.
#include "run_upd.h"
#include "temp_dir.h"
#include "upd/io/cloud_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace upd {
namespace {

using test::CmdResult;
using test::runCommand;
using test::runUpd;
using test::TempDir;

constexpr std::size_t kWidth = 64, kHeight = 48;

// An organized frame of a step (5 cm pixels, 2 m from the origin everywhere) in which every
// third pixel is invalid, as a depth camera's holes are. Returns the valid point count.
std::size_t writeFrameWithHoles(const std::string& path) {
  core::PointCloud c;
  c.resizeOrganized(kWidth, kHeight);
  std::size_t valid = 0;
  for (std::size_t v = 0; v < kHeight; ++v) {
    for (std::size_t u = 0; u < kWidth; ++u) {
      if ((u + v) % 3 == 0) continue;
      const std::size_t i = v * kWidth + u;
      c.x[i] = 2.0f + 0.05f * float(u);
      c.y[i] = 2.0f + 0.05f * float(v);
      c.z[i] = u > 40 ? 0.3f : 0.0f;
      ++valid;
    }
  }
  io::writePcd(path, c);
  return valid;
}

std::string headerOf(const std::string& ply) {
  std::ifstream in(ply, std::ios::binary);
  std::string header, line;
  while (std::getline(in, line) && line != "end_header") header += line + "\n";
  return header;
}

TEST(ScoredCloudFile, HoldsTheValidPointsOrEveryPixelOnRequest) {
  TempDir dir;
  const std::size_t valid = writeFrameWithHoles(dir.file("frame.pcd"));
  const CmdResult a = runUpd("analyze " + dir.file("frame.pcd") + " --no-preprocess --output " +
                             dir.file("valid.ply"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  const core::PointCloud back = io::readPly(dir.file("valid.ply"));
  EXPECT_EQ(back.size(), valid);
  for (std::size_t i = 0; i < back.size(); ++i) {
    ASSERT_TRUE(std::isfinite(back.x[i]) && std::isfinite(back.y[i]) && std::isfinite(back.z[i]))
        << "vertex " << i;
  }
  const std::string header = headerOf(dir.file("valid.ply"));
  for (const char* p : {"scalar_zeta", "scalar_label", "scalar_cost", "quality"}) {
    EXPECT_NE(header.find(p), std::string::npos) << p << " in\n" << header;
  }

  const CmdResult o = runUpd("analyze " + dir.file("frame.pcd") + " --no-preprocess --organized " +
                             "--output " + dir.file("organized.ply"));
  ASSERT_EQ(o.exit_code, 0) << o.output;
  EXPECT_EQ(io::readPly(dir.file("organized.ply")).size(), kWidth * kHeight);
  const std::string organized = headerOf(dir.file("organized.ply"));
  EXPECT_NE(organized.find("comment width 64\ncomment height 48\n"), std::string::npos)
      << organized;
}

// CloudCompare's command-line mode, as a user scripts it: load the PLY, save it as ASCII with
// a header that names every loaded scalar field.
TEST(ScoredCloudFile, CloudCompareLoadsTheFieldsAndNoPointAtTheOrigin) {
  if (std::system("command -v CloudCompare >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "CloudCompare not found (apt-get install cloudcompare)";
  }
  TempDir dir;
  const std::size_t valid = writeFrameWithHoles(dir.file("frame.pcd"));
  ASSERT_EQ(runUpd("analyze " + dir.file("frame.pcd") + " --no-preprocess --output " +
                   dir.file("scored.ply"))
                .exit_code,
            0);
  // The offscreen Qt platform needs no display (no xvfb).
  const CmdResult cc = runCommand("QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP -O " +
                                  dir.file("scored.ply") + " -C_EXPORT_FMT ASC -ADD_HEADER " +
                                  "-SAVE_CLOUDS FILE " + dir.file("cc.asc"));
  ASSERT_EQ(cc.exit_code, 0) << cc.output;
  std::ifstream in(dir.file("cc.asc"));
  ASSERT_TRUE(in) << cc.output;
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  ASSERT_EQ(line.rfind("//", 0), 0u) << line;
  std::istringstream names(line.substr(2));
  std::vector<std::string> columns;
  for (std::string n; names >> n;) columns.push_back(n);
  for (const char* field : {"zeta", "label", "cost", "rx", "ry", "rz", "Nx"}) {
    EXPECT_NE(std::find(columns.begin(), columns.end(), field), columns.end())
        << field << " not loaded: " << line;
  }
  std::size_t rows = 0, at_origin = 0;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    double x = NAN, y = NAN, z = NAN;
    if (!(row >> x >> y >> z)) continue;
    ++rows;
    if (std::abs(x) < 1e-6 && std::abs(y) < 1e-6 && std::abs(z) < 1e-6) ++at_origin;
  }
  EXPECT_EQ(rows, valid);
  EXPECT_EQ(at_origin, 0u);
}

}  // namespace
}  // namespace upd
