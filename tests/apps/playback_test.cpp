// `upd simulate` and `upd playback` as a user runs them: every rawlog in ../shared/data plays
// back and writes every export; the simulated run's fused map agrees with the world's ground
// truth; bad input stops cleanly with nothing written.
#include "run_upd.h"
#include "temp_dir.h"
#include "test_data.h"
#include "upd/maps/traversability_octree.h"
#include "upd/mrpt_bridge/rawlog_reader.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <mrpt/opengl/COpenGLScene.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sys/wait.h>

namespace upd {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

using test::CmdResult;
using test::runUpd;

const std::string kConfig = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect.ini";

json readJson(const fs::path& p) { return json::parse(std::ifstream(p)); }

// OctoMap's own converter (Debian's octomap-tools), as a user would try it: map.ot to .bt.
void expectConvertOctreeOpens(const octomap::AbstractOcTree& tree, const fs::path& ot) {
  if (std::system("command -v convert_octree >/dev/null 2>&1") != 0) {
    std::printf("[ SKIPPED  ] convert_octree not found (apt-get install octomap-tools)\n");
    return;
  }
  const fs::path bt = ot.parent_path() / "converted.bt";
  const CmdResult r = test::runCommand("convert_octree '" + ot.string() + "' '" + bt.string() + "'");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  octomap::OcTree converted(bt.string());
  // Its .bt is the maximum-likelihood tree, pruned: fewer nodes, the same resolution.
  EXPECT_EQ(converted.size() > 0, tree.size() > 0) << r.output;
  EXPECT_LE(converted.size(), tree.size());
  EXPECT_DOUBLE_EQ(converted.getResolution(), tree.getResolution());
  fs::remove(bt);
}

void expectAllExports(const fs::path& out) {
  for (const char* f : {"map.png", "map.pgm", "map.yaml", "map.ot", "map.bt", "map_colour.ot",
                        "map_traversability.ot", "map.3Dscene", "summary.json"}) {
    EXPECT_TRUE(fs::exists(out / f)) << (out / f);
  }
  for (const auto& e : fs::directory_iterator(out)) {
    EXPECT_EQ(e.path().string().find(".tmp-"), std::string::npos) << e.path();
  }
  // The .bt opens in liboctomap as a plain OcTree, map.ot as a standard ColorOcTree (what
  // any OctoMap program reads), map_traversability.ot with our reader.
  octomap::OcTree bt((out / "map.bt").string());
  EXPECT_GT(bt.getResolution(), 0.0);
  std::unique_ptr<octomap::AbstractOcTree> ot(octomap::AbstractOcTree::read((out / "map.ot").string()));
  ASSERT_NE(ot, nullptr);
  EXPECT_EQ(ot->getTreeType(), "ColorOcTree");
  EXPECT_NE(dynamic_cast<octomap::ColorOcTree*>(ot.get()), nullptr);
  EXPECT_NO_THROW(maps::readTraversabilityOt((out / "map_traversability.ot").string()));
  expectConvertOctreeOpens(*ot, out / "map.ot");
  // The .3Dscene reloads in MRPT (what SceneViewer3D does): ground plane, cells, path.
  mrpt::opengl::COpenGLScene scene;
  ASSERT_TRUE(scene.loadFromFile((out / "map.3Dscene").string()));
  EXPECT_EQ(scene.getViewport()->size(), 3u);
}

TEST(Playback, EveryRawlogInSharedDataPlaysBack) {
  const fs::path data = test::sharedDataDir() / "mrpt";
  if (!fs::is_directory(data)) GTEST_SKIP() << data << " not found; skipped";
  std::size_t n = 0;
  for (const auto& e : fs::directory_iterator(data)) {
    if (e.path().extension() != ".rawlog") continue;
    SCOPED_TRACE(e.path().string());
    const test::TempDir tmp(e.path().stem().string());
    const fs::path& out = tmp.path();
    const CmdResult r = runUpd("playback " + e.path().string() + " --config " + kConfig +
                               " --output " + out.string() + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    expectAllExports(out);
    const json s = readJson(out / "summary.json");
    EXPECT_GT(s["frames_read"].get<std::size_t>(), 0u);
    if (e.path().filename().string().find("SENA") != std::string::npos) {
      // A 2D laser dataset: every frame is skipped, with the reason, and odometry is tracked.
      EXPECT_EQ(s["frames_processed"], 0);
      EXPECT_EQ(s["frames_skipped"]["CObservation2DRangeScan has no 3D points (a planar laser scan)"], 225);
    } else {
      EXPECT_GE(s["frames_processed"].get<std::size_t>(), 1u);
      EXPECT_GT(s["grid"]["known"].get<std::size_t>(), 0u);
    }
    ++n;
  }
  EXPECT_EQ(n, 4u);
}

TEST(Playback, GroundRawlogFloorIsTraversableAtTheRightHeight) {
  UPD_REQUIRE_SHARED_FILE(rawlog, "mrpt/test-3d-obs-ground.rawlog");
  const test::TempDir tmp("ground");
  const fs::path& out = tmp.path();
  const CmdResult r = runUpd("playback " + rawlog + " --config " + kConfig + " --output " +
                             out.string() + " --quiet --ply --output-rawlog");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(out / "summary.json");
  EXPECT_GT(s["grid"]["known"].get<std::size_t>(), 50u);
  EXPECT_EQ(s["grid"]["non_traversable"], 0);  // a flat floor
  EXPECT_TRUE(fs::exists(out / "frames" / "000000.ply"));
  // The annotated rawlog holds the original observation and the UPD point cloud beside it.
  mrpt_bridge::RawlogReader reader((out / "annotated.rawlog").string());
  mrpt_bridge::RawlogEntry entry;
  std::size_t entries = 0, clouds = 0;
  while (reader.next(entry)) {
    ++entries;
    clouds += entry.className() == "CObservationPointCloud";
  }
  EXPECT_EQ(entries, 2u);
  EXPECT_EQ(clouds, 1u);
}

// The README's main job: a simulated run through the mixed world, played back with its
// ground-truth poses, gives a map whose non-traversable cells match the world's truth; with the
// paper's pre-processing (dune-kinect.ini) and at sensor rate (dune-kinect-realtime.ini).
TEST(Playback, SimulatedRunAgreesWithGroundTruth) {
  const test::TempDir tmp("sim");
  const fs::path& dir = tmp.path();
  const std::string rawlog = (dir / "mixed.rawlog").string();
  const CmdResult sim = runUpd("simulate --world mixed --output " + rawlog);
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  for (const char* f : {"mixed.rawlog", "mixed.gt.tum", "mixed.truth.pgm", "mixed.truth.yaml"}) {
    ASSERT_TRUE(fs::exists(dir / f)) << f;
  }
  const std::string realtime = std::string(UPD_SOURCE_DIR) + "/config/dune-kinect-realtime.ini";
  for (const std::string& config : {kConfig, realtime}) {
    SCOPED_TRACE(config);
    const fs::path out = dir / fs::path(config).stem();
    const CmdResult r =
        runUpd("playback " + rawlog + " --config " + config + " --output " + out.string() +
               " --poses " + (dir / "mixed.gt.tum").string() + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    expectAllExports(out);
    const json s = readJson(out / "summary.json");
    std::printf("simulated run, %s: %s\n", fs::path(config).filename().c_str(),
                s["ground_truth"].dump().c_str());
    EXPECT_EQ(s["pose_source"], "ground truth");
    EXPECT_EQ(s["frames_processed"], s["frames_read"]);
    EXPECT_GE(s["ground_truth"]["scores"]["precision"].get<double>(), 0.9);
    EXPECT_GE(s["ground_truth"]["scores"]["recall"].get<double>(), 0.9);
    EXPECT_GT(s["ground_truth"]["scores"]["truth_non_traversable_cells_observed"].get<int>(), 50);
  }
}

TEST(Playback, FrameSelectionAndOdometryPoses) {
  UPD_REQUIRE_SHARED_FILE(rawlog, "mrpt/2006-01ENE-21-SENA_Telecom_Faculty_one_loop_only.rawlog");
  const test::TempDir tmp("select");
  const fs::path& out = tmp.path();
  const CmdResult r = runUpd("playback " + rawlog + " --config " + kConfig + " --output " +
                             out.string() + " --quiet --from 10 --to 49 --every 5");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = readJson(out / "summary.json");
  EXPECT_EQ(s["frames_skipped"]["outside --from/--to/--every"], 225 - 8);
  EXPECT_EQ(s["pose_source"], "odometry actions");
}

TEST(Playback, BadInputStopsWithOneLineAndWritesNothing) {
  const test::TempDir tmp("bad");
  const fs::path& dir = tmp.path();
  // A truncated rawlog.
  UPD_REQUIRE_SHARED_FILE(good, "mrpt/tests_rgbd.rawlog");
  {
    std::ifstream in(good, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir / "cut.rawlog", std::ios::binary).write(bytes.data(), bytes.size() / 2);
  }
  std::ofstream(dir / "typo.ini") << "[UpdParams]\nradius_mm = 0.5\n";
  struct Case {
    std::string args, expected;
  };
  for (const Case& c : std::vector<Case>{
           {(dir / "cut.rawlog").string() + " --config " + kConfig, (dir / "cut.rawlog").string()},
           {(dir / "missing.rawlog").string() + " --config " + kConfig, "missing.rawlog"},
           {good + " --config " + (dir / "none.ini").string(), "none.ini: not found"},
           {good + " --config " + (dir / "typo.ini").string(), "unknown key 'radius_mm'"},
           {good + " --config " + kConfig + " --every 0", "--every = 0"},
       }) {
    SCOPED_TRACE(c.args);
    const fs::path out = dir / "out";
    const CmdResult r = runUpd("playback " + c.args + " --output " + out.string() + " --quiet");
    EXPECT_NE(r.exit_code, 0);
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
    EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
    EXPECT_FALSE(fs::exists(out)) << "the error left the output folder";
  }
}

}  // namespace
}  // namespace upd
