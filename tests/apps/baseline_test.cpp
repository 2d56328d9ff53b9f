// `upd baseline` as a user runs it on the generated 20 deg ramp (the paper's Fig. 5): the
// roughness index labels the smooth ramp body non-traversable, the UPD in the same file does not.
#include "run_upd.h"
#include "temp_dir.h"
#include "upd/io/cloud_io.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <fstream>

namespace {

using upd::test::CmdResult;
using upd::test::runUpd;

TEST(BaselineCommand, RoughnessFlagsTheRampBodyTheUpdDoesNot) {
  upd::test::TempDir dir("baseline");
  ASSERT_EQ(runUpd("scene ramp --spacing-m 0.02 --output " + dir.file("ramp.ply")).exit_code, 0);
  const CmdResult r = runUpd("baseline " + dir.file("ramp.ply") + " --radius-m 0.5 --output " +
                             dir.file("rough.ply") + " --stats-json " + dir.file("rough.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const CmdResult a = runUpd("analyze " + dir.file("ramp.ply") + " --radius-m 0.5 --output " +
                             dir.file("upd.ply"));
  ASSERT_EQ(a.exit_code, 0) << a.output;
  // The body's centre line, farther than d_m from the ramp's sides and borders.
  auto body = [](float x, float y) { return x > 0.6f && x < 1.4f && std::abs(y) < 0.2f; };
  for (const char* file : {"rough.ply", "upd.ply"}) {
    const auto ply = upd::io::readPly(dir.file(file));
    ASSERT_GT(ply.size(), 1000u);
  }
  std::ifstream in(dir.file("rough.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_DOUBLE_EQ(j["radius_m"].get<double>(), 0.5);
  EXPECT_GT(j["roughness"]["non_traversable"].get<int>(), 0);
  // The label of each point of a scored PLY (binary, the columns upd analyze writes).
  auto labelsOnBody = [&](const std::string& file) {
    std::ifstream f(dir.file(file), std::ios::binary);
    std::string line;
    std::size_t n = 0;
    while (std::getline(f, line) && line != "end_header")
      if (line.rfind("element vertex ", 0) == 0) n = std::stoul(line.substr(15));
    std::size_t on_body = 0, non_trav = 0;
    for (std::size_t i = 0; i < n; ++i) {
      char buf[10 * 4 + 1 + 2 * 4];  // x y z nx ny nz rx ry rz zeta, label (uchar), cost quality
      f.read(buf, sizeof buf);
      float x, y;
      std::memcpy(&x, buf, 4);
      std::memcpy(&y, buf + 4, 4);
      if (!body(x, y)) continue;
      ++on_body;
      non_trav += buf[40] == 1 ? 1 : 0;
    }
    EXPECT_GT(on_body, 300u);
    return double(non_trav) / double(on_body);
  };
  EXPECT_GT(labelsOnBody("rough.ply"), 0.99) << "roughness: tan(20 deg) d_m / 2 = 0.09 m > 0.05 m";
  EXPECT_LT(labelsOnBody("upd.ply"), 0.01) << "UPD: a plane, whatever its slope";
}

TEST(BaselineCommand, BadOptionIsAUsageError) {
  upd::test::TempDir dir("baseline-usage");
  const CmdResult r = runUpd("baseline missing.ply");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--output"), std::string::npos) << r.output;
}

}  // namespace
