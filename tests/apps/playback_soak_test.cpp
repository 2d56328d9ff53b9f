// A soak through `upd playback` as a user runs it: `upd simulate` records 10,000 frames (80 x 60
// depth images, a frame every 0.25 m: 18 laps of the loop world's 140 m course) and `upd
// playback` plays them. summary.json's memory trace (the resident memory every 1,000 frames)
// stays flat once the course has been seen: the grid's window, the octree's box and the tiles
// kept of the places left are the whole working set. The map built in two halves with a save and
// a reload between equals the one built in one go: tests/maps/soak_test.cpp (Soak.*InTwoHalves*,
// the grid state file and the .ot the playback writes).
//
// UPD_SOAK_FRAMES=N plays N frames instead (docs/RELIABILITY.md, "Long runs").
#include "run_upd.h"
#include "sanitizer.h"
#include "temp_dir.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

namespace fs = std::filesystem;
using json = nlohmann::json;
using upd::test::CmdResult;
using upd::test::runUpd;

namespace {

long soakFrames() {
  const char* env = std::getenv("UPD_SOAK_FRAMES");
  return env && std::atol(env) >= 3000 ? std::atol(env) : 10000;
}

// The realtime playback config with a coarser, shorter-ranged octree (0.2 m voxels, rays to
// 3 m): its ray casting is most of a frame's time at this resolution.
std::string soakPlaybackConfig() {
  std::ifstream in(std::string(UPD_SOURCE_DIR) + "/config/dune-kinect-realtime.ini");
  std::ostringstream out;
  std::string line, section;
  const std::regex header(R"(\s*\[(\w+)\].*)"), octree_key(R"(\s*(resolution_m|max_range_m)\s*=.*)");
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_match(line, m, header)) section = m[1];
    if (section == "OctreeParams" && std::regex_match(line, octree_key)) continue;
    out << line << "\n";
  }
  out << "[OctreeParams]\nresolution_m = 0.2\nmax_range_m = 3.0\n";
  return out.str();
}

}  // namespace

TEST(PlaybackSoak, MemoryIsFlatOnceTheCourseIsMapped) {
  const long frames = soakFrames();
  const upd::test::TempDir tmp("soak");
  const fs::path& dir = tmp.path();
  std::ofstream(dir / "sim.ini") << "[SimulationParams]\nframe_spacing_m = 0.25\n"
                                    "[CameraMountParams]\nimage_downscale = 8\n";
  std::ofstream(dir / "play.ini") << soakPlaybackConfig();
  // One OpenMP thread: the soak measures memory; two would spin against a parallel ctest run.
  const std::string one_thread = "OMP_NUM_THREADS=1 ";
  const std::string rawlog = (dir / "soak.rawlog").string();
  const CmdResult sim = upd::test::runCommand(
      one_thread + UPD_BINARY + " simulate --world loop --frames " + std::to_string(frames) +
      " --distance-m " + std::to_string(frames) + " --config " + (dir / "sim.ini").string() +
      " --output " + rawlog);
  ASSERT_EQ(sim.exit_code, 0) << sim.output;

  const fs::path out = dir / "map";
  const CmdResult r = upd::test::runCommand(
      one_thread + UPD_BINARY + " playback " + rawlog + " --config " +
      (dir / "play.ini").string() + " --poses " + (dir / "soak.gt.tum").string() +
      " --output " + out.string() + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["end"], "complete");
  ASSERT_EQ(s["frames_processed"].get<long>(), frames);
  const json& trace = s["memory"]["trace"];
  ASSERT_EQ(static_cast<long>(trace.size()), frames / 1000) << trace.dump();

  // The working set is reached after the first laps (a lap is ~580 frames): from frame 2,000 on
  // the resident memory grows by less than 8 MiB (allocator slack; the per-frame timings and
  // the trajectory add 32 bytes a frame) and the maps' own bytes by less than 10 %.
  const json& settled = trace[1];
  ASSERT_EQ(settled["frames"], 2000);
  const std::size_t rss0 = settled["rss_bytes"], maps0 = settled["grid_bytes"].get<std::size_t>() +
                                                         settled["octree_bytes"].get<std::size_t>();
  std::size_t rss_max = rss0, maps_max = maps0;
  for (const json& t : trace) {
    std::printf("frame %6ld: RSS %6.1f MiB, grid %5.1f MiB, octree %5.1f MiB\n",
                t["frames"].get<long>(), t["rss_bytes"].get<double>() / 1048576,
                t["grid_bytes"].get<double>() / 1048576, t["octree_bytes"].get<double>() / 1048576);
    if (t["frames"].get<long>() < 2000) continue;
    rss_max = std::max<std::size_t>(rss_max, t["rss_bytes"]);
    maps_max = std::max<std::size_t>(
        maps_max, t["grid_bytes"].get<std::size_t>() + t["octree_bytes"].get<std::size_t>());
  }
  EXPECT_GT(rss0, 0u);
#if defined(UPD_TEST_UNDER_ASAN)
  // An instrumented `upd` (this test is built as `upd` is): AddressSanitizer's quarantine and
  // padding move its resident memory by tens of MiB from sample to sample (572-612 MiB over
  // 10,000 frames), which measures the sanitizer's allocator, not the maps; their bytes are
  // checked below.
#else
  EXPECT_LE(rss_max, rss0 + (8u << 20)) << trace.dump();
#endif
  EXPECT_LE(maps_max, maps0 + maps0 / 10) << trace.dump();
  // The exported maps hold the whole course.
  EXPECT_GT(s["grid"]["known"].get<std::size_t>(), 30000u);
}
