// A long simulated run as a user runs it: `upd simulate --world loop --distance-m 300` at the
// reduced camera resolution, played back with its ground-truth poses. The exported maps hold the
// whole run (the first metres too, long after they left the rolling window), agree with the
// world's truth as the short run does, and summary.json reports the memory the run took.
#include "run_upd.h"
#include "temp_dir.h"
#include "upd/io/ros_map.h"
#include "upd/maps/traversability_octree.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using json = nlohmann::json;
using upd::test::CmdResult;
using upd::test::runUpd;

namespace {

struct Pose2 {
  double x, y, yaw;
};

// The TUM poses' planar part.
std::vector<Pose2> readTum(const fs::path& path) {
  std::vector<Pose2> out;
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    double t, x, y, z, qx, qy, qz, qw;
    s >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
    out.push_back({x, y, std::atan2(2 * (qw * qz + qx * qy), 1 - 2 * (qy * qy + qz * qz))});
  }
  return out;
}

}  // namespace

TEST(LongRun, ThreeHundredMetresPlayBackIntoOneMapOfTheWholeRun) {
  const upd::test::TempDir tmp("long");
  const fs::path& dir = tmp.path();
  // The README's commands. The CI-friendly resolution: 160 x 120 frames every 0.5 m.
  const std::string rawlog = (dir / "loop.rawlog").string();
  const CmdResult sim = runUpd(std::string("simulate --world loop --distance-m 300 --config ") +
                               UPD_SOURCE_DIR + "/config/sim-long-run.ini --output " + rawlog);
  ASSERT_EQ(sim.exit_code, 0) << sim.output;
  EXPECT_NE(sim.output.find("over 300.0 m"), std::string::npos) << sim.output;

  const fs::path out = dir / "map";
  const CmdResult r = runUpd("playback " + rawlog + " --config " + UPD_SOURCE_DIR +
                             "/config/dune-kinect-realtime.ini --poses " +
                             (dir / "loop.gt.tum").string() + " --output " + out.string() +
                             " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json s = json::parse(std::ifstream(out / "summary.json"));
  std::printf("300 m run: %s\n  memory: %s\n", s["ground_truth"]["scores"].dump().c_str(),
              s["memory"].dump().c_str());
  EXPECT_EQ(s["frames_processed"], s["frames_read"]);
  EXPECT_GE(s["ground_truth"]["scores"]["precision"].get<double>(), 0.9);
  EXPECT_GE(s["ground_truth"]["scores"]["recall"].get<double>(), 0.9);
  EXPECT_GT(s["ground_truth"]["scores"]["truth_non_traversable_cells_observed"].get<int>(), 300);

  // The run left the working set (tiles were kept) and the map bytes stay within the bound.
  const json& m = s["memory"];
  EXPECT_GT(m["vm_hwm_bytes"].get<std::size_t>(), 0u);
  EXPECT_GT(m["grid_tiles"].get<std::size_t>(), 0u);
  EXPECT_LE(m["grid_tile_bytes"].get<std::size_t>(),
            m["grid_tiles"].get<std::size_t>() * m["grid_max_bytes_per_tile"].get<std::size_t>());
  EXPECT_GT(m["octree_tiles"].get<std::size_t>(), 0u);

  // The exported grid covers the whole path: the ground 1.5 m ahead of every pose is known.
  const upd::io::RosMap map = upd::io::readRosMap((out / "map.yaml").string());
  const std::vector<Pose2> poses = readTum(dir / "loop.gt.tum");
  ASSERT_GT(poses.size(), 600u);
  std::size_t unknown = 0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Pose2& p = poses[k];
    const bool known = map.labelAt(p.x + 1.5 * std::cos(p.yaw), p.y + 1.5 * std::sin(p.yaw)) !=
                       upd::core::Label::Unknown;
    if (k < 20) {
      EXPECT_TRUE(known) << "the first metres: pose " << k;
    }
    unknown += !known;
  }
  EXPECT_LE(unknown, poses.size() / 100) << unknown << " poses look at unknown ground";

  // So does the full octree: the start and the far corner of the course.
  const auto tree = upd::maps::readTraversabilityOt((out / "map_traversability.ot").string());
  int near_start = 0, far_corner = 0;
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it) {
    if (!it->hasTraversability()) continue;
    near_start += std::hypot(it.getX() - 6.5, it.getY() - 5.0) < 1.0;
    far_corner += std::hypot(it.getX() - 55.0, it.getY() - 23.5) < 1.0;
  }
  EXPECT_GT(near_start, 50);
  EXPECT_GT(far_corner, 50);
}
