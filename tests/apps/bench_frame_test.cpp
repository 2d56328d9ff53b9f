// upd_bench --frame: a frame of the user's (a depth PNG, an organized cloud) is timed in the
// frame tables beside the report's own, and a frame it cannot take (or a calibration with no depth
// image to apply it to) is a one-line error.
#include "run_upd.h"
#include "temp_dir.h"

#include "upd/mrpt_bridge/depth_files.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <string>

#ifdef UPD_BENCH_BINARY

namespace {

using nlohmann::json;
using upd::test::CmdResult;

CmdResult bench(const std::string& args) {
  return upd::test::runCommand(std::string(UPD_BENCH_BINARY) + " " + args);
}

// A level Kinect 0.6 m above a floor that ends at a wall 4 m ahead (the optical frame: y down).
upd::core::DepthImage floorAndWall() {
  const upd::core::CameraIntrinsics k;
  upd::core::DepthImage d;
  d.width = k.width, d.height = k.height;
  d.depth_m.assign(static_cast<std::size_t>(d.width) * d.height, 4.0f);
  for (int v = 0; v < d.height; ++v) {
    const double down = (v - k.cy) / k.fy;  // (the ray's y at z = 1)
    if (down <= 0.6 / 4.0) continue;        // (the wall)
    for (int u = 0; u < d.width; ++u) d.depth_m[static_cast<std::size_t>(v) * d.width + u] =
        static_cast<float>(0.6 / down);
  }
  return d;
}

}  // namespace

TEST(BenchFrame, AUsersDepthPngIsTimedBesideTheReportsFrames) {
  const upd::test::TempDir dir;
  const std::string png = dir.file("floor_wall.png");
  upd::mrpt_bridge::writeDepthPng(png, floorAndWall());
  const std::string report = dir.file("report.json");
  // (--data: an empty folder, so that the real frames are skipped and the run takes seconds)
  const CmdResult r = bench("--frames-only --repeats 1 --data " + dir.path().string() +
                            " --frame " + png + " --json " + report);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const json j = json::parse(std::ifstream(report));
  const json& frames = j["frames"];
  ASSERT_EQ(frames.size(), 4u) << r.output;  // office1, region_growing, the generated, ours
  const json& ours = frames[3];
  EXPECT_EQ(ours["name"], "floor_wall");
  EXPECT_EQ(ours["source"], png);
  EXPECT_EQ(ours["starts_from"], "depth image");
  EXPECT_GT(ours["points_scored"].get<double>(), 200000) << ours.dump();
  EXPECT_GT(ours["one_core_ms"].get<double>(), 0) << ours.dump();
  EXPECT_NE(r.output.find("floor_wall: frame pipeline, one core (median)"), std::string::npos)
      << r.output;
  // (As read, before the tables: a wrong up or scale shows there.)
  EXPECT_NE(r.output.find("your frame floor_wall: " + png +
                          ", depth image of 640 x 480, up 0.000,-1.000,0.000"),
            std::string::npos)
      << r.output;
  EXPECT_EQ(j["your_frames"][0]["up"], json::array({0.0, -1.0, 0.0}));
}

TEST(BenchFrame, AFrameItCannotTakeIsAOneLineError) {
  const upd::test::TempDir dir;
  const std::string xyz = dir.file("three.xyz");
  std::ofstream(xyz) << "0 0 1\n0 1 1\n1 0 1\n";
  const std::string data = " --frames-only --repeats 1 --data " + dir.path().string();
  const struct {
    std::string args, message;
  } cases[] = {
      {"--frame " + dir.file("missing.pcd"), dir.file("missing.pcd")},
      {"--frame " + xyz, xyz + ": not an organized cloud (3 points in one row)"},
      {"--frame " + xyz + " --up 0,0,0", "--up 0,0,0: the zero vector has no direction"},
      {"--frame " + xyz + " --up 0,1", "--up 0,1: three numbers X,Y,Z"},
      {"--frame " + xyz + " --depth-scale -1", "--depth-scale must be > 0"},
      {"--frame " + xyz + " --intrinsics " + dir.file("k.yaml"),
       "--intrinsics " + dir.file("k.yaml") + ": a calibration for depth images, and no --frame "
       "is a .png"},
  };
  for (const auto& c : cases) {
    const CmdResult r = bench(c.args + data);
    EXPECT_EQ(r.exit_code, 1) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find("upd_bench: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.args << "\n" << r.output;
  }
}

#endif  // UPD_BENCH_BINARY
