// `upd evaluate` end to end on a small semantic-LiDAR layout written from a generated scene,
// and its errors; the classifier key of the configs.
#include "run_upd.h"
#include "temp_dir.h"

#include "upd/io/kitti_bin.h"
#include "upd/sim/scenes.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace upd {
namespace {

namespace fs = std::filesystem;
using test::runUpd;

const std::string kClassMap = std::string(UPD_SOURCE_DIR) + "/share/class_maps/semantic-kitti.txt";
const std::string kKinect = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect.ini";

// A SemanticKITTI sequence folder holding the step scene: road (40) and building (50) labels,
// instance ids in the upper bits.
fs::path writeSequence(const fs::path& dir) {
  sim::SceneParams sp;
  sp.spacing_m = 0.04;
  const sim::Scene s = sim::makeScene("step", sp);
  fs::create_directories(dir / "velodyne");
  fs::create_directories(dir / "labels");
  io::writeKittiBin((dir / "velodyne" / "000000.bin").string(), s.cloud);
  std::ofstream out(dir / "labels" / "000000.label", std::ios::binary);
  for (core::Label l : s.truth) {
    const std::uint32_t v = (3u << 16) | (l == core::Label::NonTraversable ? 50u : 40u);
    out.write(reinterpret_cast<const char*>(&v), 4);
  }
  return dir;
}

const std::string kOnlyInput = " --no-generated --no-shared --no-classifier --radius-m 0.3,0.5";

TEST(Evaluate, SemanticLayoutGivesTablesJsonAndPlots) {
  const test::TempDir tmp;
  const fs::path seq = writeSequence(tmp.path() / "08"), out = tmp.path() / "out";
  const auto r = runUpd("evaluate " + seq.string() + " --class-map " + kClassMap + " --config " +
                        kKinect + " --output " + out.string() + kOnlyInput);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(std::ifstream(out / "evaluation.json"));
  ASSERT_EQ(j["groups"].size(), 1u);
  EXPECT_EQ(j["groups"][0]["group"], "semantic LiDAR (semantic-kitti)");
  bool upd_seen = false;
  for (const auto& m : j["groups"][0]["per_point"]) {
    EXPECT_GT(m["auc"].get<double>(), 0.5) << m["detector"];  // every score beats chance
    if (m["detector"] == "UPD (zeta and slope)" && m["d_m"] == 0.3) {
      upd_seen = true;
      EXPECT_EQ(m["recall"].get<double>(), 1.0);  // the riser and its edges are all flagged
      EXPECT_GT(m["f1"].get<double>(), 0.3);  // the band about d_m wide around the riser is flagged too
    }
  }
  EXPECT_TRUE(upd_seen);
  EXPECT_EQ(j["groups"][0]["per_cell"].size(), j["groups"][0]["per_point"].size());
  EXPECT_TRUE(fs::exists(out / "evaluation.md"));
  EXPECT_GT(fs::file_size(out / "roc_semantic-lidar-semantic-kitti_d0.3.png"), 10000u);
  EXPECT_TRUE(fs::exists(out / "roc_semantic-lidar-semantic-kitti_d0.5.png"));
}

TEST(Evaluate, ErrorsAreOneLineAndWriteNothing) {
  const test::TempDir tmp;
  const fs::path seq = writeSequence(tmp.path() / "08"), out = tmp.path() / "out";
  const auto expectError = [&](const std::string& args, const std::string& part,
                               const std::string& options = kOnlyInput) {
    const auto r = runUpd("evaluate " + args + " --output " + out.string() + options);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_NE(r.output.find(part), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(out / "evaluation.md"));
  };
  expectError(seq.string(), "--class-map");
  expectError(seq.string() + " --class-map " + kKinect, "class id");
  expectError(seq.string() + " --class-map " + kClassMap, "--radius-m",
              " --no-generated --no-shared --radius-m 0.5,x");
  {
    std::ofstream(seq / "labels" / "000000.label", std::ios::app) << "abcd";
  }
  expectError(seq.string() + " --class-map " + kClassMap, "000000.label");
  expectError((tmp.path() / "none").string() + " --class-map " + kClassMap, "no such file");
}

TEST(Evaluate, ConfigClassifierThatCannotLoadNamesTheConfigAndKey) {
  const test::TempDir tmp;
  const fs::path ini = tmp.path() / "robot.ini";
  std::ofstream(ini) << "[ClassifyParams]\nzeta_min = 0.95\nclassifier = missing.yml\n";
  const fs::path seq = writeSequence(tmp.path() / "08");
  const auto r = runUpd("analyze " + (seq / "velodyne" / "000000.bin").string() + " --config " +
                        ini.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(ini.string() + ": [ClassifyParams] classifier"), std::string::npos)
      << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
}

}  // namespace
}  // namespace upd
