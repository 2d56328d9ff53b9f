// The `upd` command as a user runs it: every cloud file in ../shared/data and every generated
// scene is analysed; bad input stops with one line naming the file, option or value, a
// non-zero exit, and no output file (not even half of one).
#include "run_upd.h"
#include "test_data.h"
#include "upd/core/version.h"
#include "upd/io/cloud_io.h"
#include "upd/mrpt_bridge/robot_config.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <regex>
#include <sys/wait.h>
#include <utility>

namespace core = upd::core;

namespace upd {
namespace {

namespace fs = std::filesystem;

using test::CmdResult;
using test::runUpd;

class Cli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("upd_cli_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::size_t filesInDir() const {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir_), {}));
  }
  fs::path dir_;
};

TEST_F(Cli, HelpListsTheCommands) {
  const CmdResult r = runUpd("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* c : {"analyze", "scene", "params"}) {
    EXPECT_NE(r.output.find(c), std::string::npos) << c;
  }
  const CmdResult a = runUpd("analyze --help");
  EXPECT_EQ(a.exit_code, 0);
  EXPECT_NE(a.output.find("--radius-m"), std::string::npos);
}

// The release CMake's project() names, what `upd --version` and every summary report.
std::string projectVersion() {
  std::ifstream in(std::string(UPD_SOURCE_DIR) + "/CMakeLists.txt");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::smatch m;
  std::regex_search(text, m, std::regex(R"(project\(upd_nav VERSION ([0-9.]+))"));
  return m.size() > 1 ? m[1].str() : "(no project version in CMakeLists.txt)";
}

TEST_F(Cli, VersionNamesTheReleaseAndWhatItWasBuiltWith) {
  const std::string v = projectVersion();
  EXPECT_EQ(core::version(), v);
  for (const char* arg : {"--version", "version"}) {
    const CmdResult r = runUpd(arg);
    EXPECT_EQ(r.exit_code, 0) << arg;
    EXPECT_NE(r.output.find("upd (UPD-Nav) " + v + "\n"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("MRPT 2."), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("optional parts: OpenNI2 "), std::string::npos) << r.output;
  }
  // The scored cloud's stats name the release that made them, as its PLY header does.
  const std::string ply = path("ramp.ply"), json_path = path("ramp.json");
  ASSERT_EQ(runUpd("scene ramp --spacing-m 0.05 --output " + ply).exit_code, 0);
  ASSERT_EQ(runUpd("analyze " + ply + " --output " + path("out.ply") + " --stats-json " +
                   json_path).exit_code,
            0);
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(json_path))["upd_nav_version"], v);
  std::ifstream scored(path("out.ply"));
  std::string line;
  std::getline(scored, line);
  std::getline(scored, line);
  std::getline(scored, line);
  EXPECT_EQ(line, "comment UPD-Nav " + v);
}

// MRPT's gui and hwdrivers (wxWidgets, GTK, FFmpeg, ...) are loaded with the viewer and the
// sensor files (the modules), not at every start of the tool.
TEST_F(Cli, TheToolLinksNeitherMrptGuiNorHwdrivers) {
  const CmdResult r = test::runCommand(std::string("ldd ") + UPD_BINARY);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  if (r.output.find("libupd_core") == std::string::npos) {
    GTEST_SKIP() << "a static build: no modules, the viewer and the sensors are linked in";
  }
  EXPECT_EQ(r.output.find("libmrpt-gui"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("libmrpt-hwdrivers"), std::string::npos) << r.output;
}

TEST_F(Cli, EveryGeneratedSceneIsAnalysed) {
  for (const char* scene : {"corner", "ramp", "step", "stairs", "ditch", "rocks"}) {
    SCOPED_TRACE(scene);
    const std::string ply = path(std::string(scene) + ".ply");
    const CmdResult s = runUpd(std::string("scene ") + scene + " --spacing-m 0.03 --noise-m 0.001 " +
                         "--output " + ply);
    ASSERT_EQ(s.exit_code, 0) << s.output;
    const core::PointCloud scene_cloud = io::readCloud(ply);
    const CmdResult a = runUpd("analyze " + ply + " --no-preprocess --output " + path("out.ply") +
                         " --stats-json " + path("out.json"));
    ASSERT_EQ(a.exit_code, 0) << a.output;
    const auto j = nlohmann::json::parse(std::ifstream(path("out.json")));
    EXPECT_EQ(j["points_in"], scene_cloud.size());
    EXPECT_EQ(j["labels"]["traversable"].get<std::size_t>() +
                  j["labels"]["non_traversable"].get<std::size_t>() +
                  j["labels"]["unknown"].get<std::size_t>(),
              scene_cloud.size());
    for (const char* key : {"points_scored", "points_invalid", "radius_m", "zeta", "labels",
                            "timing_ms"}) {
      EXPECT_TRUE(j.contains(key)) << key;
    }
    for (const char* key : {"preprocess", "normals", "upd", "classify", "total"}) {
      EXPECT_TRUE(j["timing_ms"].contains(key)) << key;
    }
    EXPECT_EQ(io::readCloud(path("out.ply")).size(), scene_cloud.size());
  }
}

TEST_F(Cli, EveryCloudFileInSharedDataIsAnalysedOrRefusedClearly) {
  const auto data = test::sharedDataDir();
  if (!fs::is_directory(data)) GTEST_SKIP() << data << " not found; skipped";
  std::size_t analysed = 0;
  for (const auto& e : fs::recursive_directory_iterator(data)) {
    const std::string ext = e.path().extension().string();
    if (ext != ".pcd" && ext != ".ply" && ext != ".xyz") continue;
    SCOPED_TRACE(e.path().string());
    const CmdResult r = runUpd("analyze " + e.path().string() + " --stats-json " + path("s.json"));
    if (e.path().filename().string().rfind("stereo_", 0) == 0) {
      // A stereo pair's grey images stored as PCD: no geometry to score.
      EXPECT_EQ(r.exit_code, 1);
      EXPECT_NE(r.output.find(e.path().string()), std::string::npos) << r.output;
      EXPECT_NE(r.output.find("x/y/z"), std::string::npos) << r.output;
      continue;
    }
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto j = nlohmann::json::parse(std::ifstream(path("s.json")));
    EXPECT_GT(j["points_in"].get<std::size_t>(), 0u);
    ++analysed;
  }
  EXPECT_GE(analysed, 7u);
}

// A floor seen by a level camera, in its optical frame (y down): with the default up (+z) it is
// a wall and nothing is traversable, which the command points out with the option that fixes
// it; with that option the floor is traversable and the note is gone.
TEST_F(Cli, CameraFrameCloudWithTheDefaultUpGetsANote) {
  {
    std::ofstream xyz(path("floor.xyz"));
    for (int i = 0; i <= 40; ++i) {
      for (int j = 0; j <= 40; ++j) xyz << -1 + 0.05 * i << " 0.7 " << 1 + 0.05 * j << "\n";
    }
  }
  const std::string note = "no point is traversable with up = 0,0,1 (the default)";
  const CmdResult plain = runUpd("analyze " + path("floor.xyz") + " --no-preprocess");
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  EXPECT_NE(plain.output.find(note), std::string::npos) << plain.output;
  EXPECT_NE(plain.output.find("--up 0,-1,0"), std::string::npos) << plain.output;
  const CmdResult up =
      runUpd("analyze " + path("floor.xyz") + " --no-preprocess --up 0,-1,0");
  ASSERT_EQ(up.exit_code, 0) << up.output;
  EXPECT_EQ(up.output.find(note), std::string::npos) << up.output;
  EXPECT_NE(up.output.find(" 0 non-traversable"), std::string::npos) << up.output;
}

// A cloud far from its sensor origin (georeferenced, airborne) under a camera's range cut-off:
// nothing is left to score, and one line says how far the points lie and what to set.
TEST_F(Cli, ARangeCutOffThatRemovesEveryPointGetsANote) {
  {
    std::ofstream xyz(path("far.xyz"));
    for (int i = 0; i <= 20; ++i) {
      for (int j = 0; j <= 20; ++j) xyz << 1000 + 0.1 * i << " " << 0.1 * j << " 0\n";
    }
  }
  const std::string config = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect.ini";
  const CmdResult cut = runUpd("analyze " + path("far.xyz") + " --config " + config);
  ASSERT_EQ(cut.exit_code, 0) << cut.output;
  EXPECT_NE(cut.output.find("441 points in, 0 scored"), std::string::npos) << cut.output;
  EXPECT_NE(cut.output.find("upd analyze: note: the range cut-off (0.4-5 m from the sensor "
                            "origin 0,0,0) removed every point: they lie 1000-1002 m from it"),
            std::string::npos)
      << cut.output;
  const CmdResult kept =
      runUpd("analyze " + path("far.xyz") + " --config " + config + " --no-preprocess");
  ASSERT_EQ(kept.exit_code, 0) << kept.output;
  EXPECT_EQ(kept.output.find("range cut-off"), std::string::npos) << kept.output;
  EXPECT_NE(kept.output.find("441 points in, 441 scored"), std::string::npos) << kept.output;
}

TEST_F(Cli, MissingInputNamesTheFileAndWritesNothing) {
  const CmdResult r = runUpd("analyze " + path("nope.pcd") + " --output " + path("o.ply"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find(path("nope.pcd")), std::string::npos) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_EQ(filesInDir(), 0u);
}

TEST_F(Cli, CorruptInputNamesTheFileAndWritesNothing) {
  std::ofstream(path("bad.ply")) << "ply\nformat binary_little_endian 1.0\nelement vertex 1000\n"
                                    "property float x\nproperty float y\nproperty float z\n"
                                    "end_header\n\x01\x02";
  const CmdResult r = runUpd("analyze " + path("bad.ply") + " --output " + path("o.ply") +
                       " --stats-json " + path("o.json"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find(path("bad.ply")), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("o.ply")));
  EXPECT_FALSE(fs::exists(path("o.json")));
  EXPECT_EQ(filesInDir(), 1u);  // the input only: no temporary files left behind
}

TEST_F(Cli, BadParametersNameTheFieldAndValue) {
  ASSERT_EQ(runUpd("scene corner --spacing-m 0.05 --output " + path("c.ply")).exit_code, 0);
  const std::string in = path("c.ply");
  struct Case {
    std::string args, expected;
  };
  for (const Case& c : std::vector<Case>{
           {"--radius-m -1", "UpdParams.radius_m = -1: must be > 0"},
           {"--voxel-m 0", "PreprocessParams.voxel_m = 0: must be > 0"},
           {"--up 0,0,0", "PipelineParams.up = 0,0,0"},
           {"--radius-m abc", "--radius-m = 'abc': not a number"},
           {"--up 1,2", "--up = '1,2': expected three numbers"},
           {"--frobnicate 3", "unknown option --frobnicate"},
           {"--config " + path("missing.ini"), "config file " + path("missing.ini") + ": not found"},
       }) {
    SCOPED_TRACE(c.args);
    const CmdResult r = runUpd("analyze " + in + " " + c.args + " --output " + path("o.ply"));
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(path("o.ply")));
  }
}

TEST_F(Cli, BadConfigValueNamesFileKeyAndValue) {
  ASSERT_EQ(runUpd("scene step --spacing-m 0.05 --output " + path("s.ply")).exit_code, 0);
  std::ofstream(path("bad.ini")) << "[UpdParams]\nradius_m = 0.5m\n";
  const CmdResult r = runUpd("analyze " + path("s.ply") + " --config " + path("bad.ini"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find(path("bad.ini") + ": [UpdParams] radius_m = '0.5m': not a number"),
            std::string::npos)
      << r.output;
}

TEST_F(Cli, NaNAndEmptyCloudsAreHandled) {
  std::ofstream(path("nan.xyz")) << "nan nan nan\n0 0 0\n0.01 0 0\n";
  const CmdResult r = runUpd("analyze " + path("nan.xyz") + " --no-preprocess --stats-json " +
                       path("n.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(std::ifstream(path("n.json")));
  EXPECT_EQ(j["points_in"], 3);
  EXPECT_EQ(j["points_scored"], 0);
  EXPECT_EQ(j["points_invalid"], 3);
  std::ofstream(path("empty.xyz")) << "# nothing\n";
  const CmdResult e = runUpd("analyze " + path("empty.xyz") + " --stats-json " + path("e.json"));
  ASSERT_EQ(e.exit_code, 0) << e.output;
  EXPECT_EQ(nlohmann::json::parse(std::ifstream(path("e.json")))["points_in"], 0);
}

// Every shipped robot config loads strictly (an unknown section or key would stop the run).
TEST_F(Cli, EveryShippedConfigLoads) {
  ASSERT_EQ(runUpd("scene step --spacing-m 0.05 --output " + path("s.ply")).exit_code, 0);
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(std::string(UPD_SOURCE_DIR) + "/config")) {
    const std::string name = e.path().filename().string();
    if (e.path().extension() != ".ini" || name.rfind("ptg", 0) == 0 || name.find("-nav") != std::string::npos) {
      continue;  // navigator (PTG) files have their own format
    }
    const CmdResult r = runUpd("analyze " + path("s.ply") + " --config " + e.path().string());
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.output;
    ++n;
  }
  EXPECT_GE(n, 3u);
}

TEST_F(Cli, ParamsMarkdownMatchesTheDocs) {
  const CmdResult r = runUpd("params --markdown");
  ASSERT_EQ(r.exit_code, 0);
  std::ifstream doc(std::string(UPD_SOURCE_DIR) + "/docs/PARAMETERS.md");
  const std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  // docs/PARAMETERS.md embeds `upd params --markdown` verbatim: regenerate it when this fails.
  EXPECT_NE(text.find(r.output), std::string::npos)
      << "docs/PARAMETERS.md is out of date; regenerate with scripts/gen-docs.sh";
}

// `upd params --ini` is a complete robot config: it loads strictly (no unknown section or key)
// and every value passes its rule. The navigation sections are listed apart (--nav-ini).
TEST_F(Cli, ParamsIniIsAValidRobotConfig) {
  const CmdResult ini = runUpd("params --ini");
  ASSERT_EQ(ini.exit_code, 0) << ini.output;
  EXPECT_EQ(ini.output.find("[NavigatorParams]"), std::string::npos);
  std::ofstream(path("all.ini")) << ini.output;
  ASSERT_EQ(runUpd("scene step --spacing-m 0.05 --output " + path("s.ply")).exit_code, 0);
  const CmdResult r = runUpd("analyze " + path("s.ply") + " --config " + path("all.ini"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  const CmdResult nav = runUpd("params --nav-ini");
  ASSERT_EQ(nav.exit_code, 0) << nav.output;
  EXPECT_NE(nav.output.find("[NavigatorParams]"), std::string::npos);
  EXPECT_NE(nav.output.find("[LoopParams]"), std::string::npos);
  EXPECT_NE(runUpd("params --ini --nav-ini").exit_code, 0);
}

// `upd params --ini` writes enum keys by name, and a name written back loads as its value.
TEST_F(Cli, ParamsIniEnumNamesRoundTrip) {
  const CmdResult ini = runUpd("params --ini");
  ASSERT_EQ(ini.exit_code, 0) << ini.output;
  std::string text = ini.output;
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"\nmethod = auto\n",
                                                                      "\nmethod = exact\n"},
                                 {"\nweighting = uniform\n", "\nweighting = gaussian\n"}}) {
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from << " not in:\n" << text;
    text.replace(at, from.size(), to);
  }
  std::ofstream(path("names.ini")) << text;
  mrpt_bridge::IniReader reader(path("names.ini"));
  core::PipelineParams p;
  mrpt_bridge::RobotConfigParts parts;
  parts.pipeline = &p;
  mrpt_bridge::readRobotConfig(reader, parts);
  EXPECT_EQ(p.upd.method, core::UpdMethod::Exact);
  EXPECT_EQ(p.normals.weighting, core::NormalWeighting::Gaussian);
  EXPECT_DOUBLE_EQ(p.upd.radius_m, core::UpdParams{}.radius_m);
  // The docs table shows the names too.
  const CmdResult r = runUpd("params --markdown");
  EXPECT_NE(r.output.find("| `method` | `auto` |"), std::string::npos);
  EXPECT_NE(r.output.find("| `weighting` | `uniform` |"), std::string::npos);
}

}  // namespace
}  // namespace upd
