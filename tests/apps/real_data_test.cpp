// The UPD on real Kinect frames from ../shared/data: every organized PCD loads and is scored,
// and on two indoor frames the open floor is traversable while floor-wall and floor-obstacle
// borders are not. Regions are found geometrically (elevation along up), not hand-labelled.
#include "exact_agreement.h"
#include "test_data.h"
#include "upd/core/kdtree.h"
#include "upd/core/normals.h"
#include "upd/core/pipeline.h"
#include "upd/io/cloud_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

namespace core = upd::core;

namespace upd {
namespace {

struct FloorStats {
  std::size_t open_floor = 0, open_floor_traversable = 0;
  std::size_t border = 0, border_non_traversable = 0;
  double openTraversableFraction() const { return double(open_floor_traversable) / open_floor; }
  double borderFlaggedFraction() const { return double(border_non_traversable) / border; }
};

// The floor is the most populated 2 cm elevation bin among points whose normal is within 15 deg
// of up; floor points lie within 5 cm of it (Kinect noise at 4-5 m is 2-3 cm, and its depth
// steps are 5 cm there); "obstacles" are points more than 10 cm above it. Open floor: floor
// points with no obstacle within d_m + the normal radius. Border: floor points within 0.1 m of
// an obstacle point that stands 10-35 cm above the floor (the foot of a wall or an object).
FloorStats floorStats(const core::PipelineResult& r, const core::PipelineParams& p) {
  const Eigen::Vector3f up = p.unitUp();
  const core::PointCloud& c = r.cloud;
  std::map<int, std::size_t> bins;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!c.isFinite(i) || !r.normals.isValid(i)) continue;
    if (r.normals.normal(i).dot(up) < std::cos(15.0 * core::kDegToRad)) continue;
    ++bins[static_cast<int>(std::floor(c.point(i).dot(up) / 0.02))];
  }
  int best = 0;
  std::size_t best_n = 0;
  for (const auto& [b, n] : bins) {
    if (n > best_n) best = b, best_n = n;
  }
  const double floor_e = (best + 0.5) * 0.02;
  core::PointCloud obstacles, feet;
  std::vector<std::size_t> floor;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!c.isFinite(i)) continue;
    const double h = c.point(i).dot(up) - floor_e;
    if (std::abs(h) < 0.05) floor.push_back(i);
    if (h > 0.10) obstacles.push_back(c.x[i], c.y[i], c.z[i]);
    if (h > 0.10 && h < 0.35) feet.push_back(c.x[i], c.y[i], c.z[i]);
  }
  const core::KdTree obstacle_tree(obstacles), feet_tree(feet);
  const float clear = static_cast<float>(p.upd.radius_m + p.normals.radius_m);
  FloorStats s;
  std::vector<std::uint32_t> nb;
  for (const std::size_t i : floor) {
    if (!r.upd.isValid(i)) continue;
    obstacle_tree.knnSearch(c.point(i), 1, nb);
    if (nb.empty() || (obstacles.point(nb[0]) - c.point(i)).norm() > clear) {
      ++s.open_floor;
      s.open_floor_traversable += r.classes.label[i] == core::Label::Traversable;
    }
    feet_tree.radiusSearch(c.point(i), 0.1f, nb);
    if (!nb.empty()) {
      ++s.border;
      s.border_non_traversable += r.classes.label[i] == core::Label::NonTraversable;
    }
  }
  std::printf("floor at %.3f m along up: %zu open-floor points (%.3f traversable), %zu border "
              "points (%.3f non-traversable)\n",
              floor_e, s.open_floor, s.openTraversableFraction(), s.border,
              s.borderFlaggedFraction());
  return s;
}

core::PipelineParams kinectParams(const Eigen::Vector3f& up) {
  core::PipelineParams p;
  p.up = up;
  return p;
}

TEST(RealData, Office1OpenFloorTraversableBordersNot) {
  UPD_REQUIRE_SHARED_FILE(path, "pcl/office1.pcd");
  const core::PointCloud cloud = io::readCloud(path);
  const core::PipelineParams p = kinectParams(Eigen::Vector3f(0, -1, 0.01f));  // level camera
  const core::PipelineResult r = core::runPipeline(cloud, p);
  const FloorStats s = floorStats(r, p);
  ASSERT_GT(s.open_floor, 100u);
  ASSERT_GT(s.border, 100u);
  EXPECT_GE(s.openTraversableFraction(), 0.9);
  EXPECT_GE(s.borderFlaggedFraction(), 0.8);
}

TEST(RealData, RegionGrowingOpenFloorTraversableBottlesAndFurnitureBordersNot) {
  UPD_REQUIRE_SHARED_FILE(path, "pcl-data/region_growing_rgb_tutorial.pcd");
  const core::PointCloud cloud = io::readCloud(path);
  // The camera looks about 32 deg down: up is the floor normal in the camera frame.
  const core::PipelineParams p = kinectParams(Eigen::Vector3f(0.06f, -0.85f, -0.53f));
  const core::PipelineResult r = core::runPipeline(cloud, p);
  const FloorStats s = floorStats(r, p);
  ASSERT_GT(s.open_floor, 100u);
  ASSERT_GT(s.border, 100u);
  EXPECT_GE(s.openTraversableFraction(), 0.9);
  EXPECT_GE(s.borderFlaggedFraction(), 0.8);
}

// Every PCD under ../shared/data that holds an organized cloud loads and is scored; the two
// image-only PCDs (a stereo pair's grey levels, no x/y/z) fail with a message saying so.
TEST(RealData, EveryOrganizedPcdLoadsAndIsScored) {
  const auto dir = test::sharedDataDir();
  if (!std::filesystem::is_directory(dir)) GTEST_SKIP() << dir << " not found; skipped";
  std::size_t scored = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir)) {
    if (e.path().extension() != ".pcd") continue;
    SCOPED_TRACE(e.path().string());
    core::PointCloud cloud;
    try {
      cloud = io::readCloud(e.path().string());
    } catch (const std::runtime_error& err) {
      EXPECT_NE(std::string(err.what()).find("x/y/z"), std::string::npos) << err.what();
      EXPECT_NE(e.path().filename().string().find("stereo_"), std::string::npos);
      continue;
    }
    if (!cloud.isOrganized()) continue;
    // Up in each file's frame, from the floor or table normals in SOURCES.md.
    const std::map<std::string, Eigen::Vector3f> ups = {
        {"office1.pcd", {0.f, -1.f, 0.01f}},
        {"region_growing_rgb_tutorial.pcd", {0.06f, -0.85f, -0.53f}},
        {"table_scene_mug_stereo_textured.pcd", {0.02f, -0.84f, -0.55f}},
        {"0000_cloud.pcd", {-1.f, 0.f, 0.f}},  // gravity-aligned, +x down
    };
    core::PipelineParams p;
    const auto up = ups.find(e.path().filename().string());
    if (up != ups.end()) p.up = up->second;
    const core::PipelineResult r = core::runPipeline(cloud, p);
    const std::size_t valid = r.cloud.size() - r.upd.invalid;
    std::printf("%s: %zu points, %zu scored, %zu traversable, %zu non-traversable\n",
                e.path().filename().c_str(), cloud.size(), valid, r.classes.traversable,
                r.classes.non_traversable);
    EXPECT_GT(valid, r.cloud.size() * 9 / 10);
    EXPECT_GT(r.classes.traversable, 0u);
    EXPECT_GT(r.classes.non_traversable, 0u);
    ++scored;
  }
  EXPECT_GE(scored, 4u);  // office1, region_growing, table_scene_mug, stair-perception
}

// The frame pipeline's default fast path on a whole 640 x 480 frame (every pixel, normals of
// 5 cm, d_m = 0.5 m: the benchmark's frame settings) against the exact path: exact normals for
// every pixel, the exact UPD (eq. 6 over a k-d tree radius search) at every 23rd pixel.
// region_growing is the frame whose zeta crowds the label threshold most (docs/PERFORMANCE.md):
// its labels agree on 99.6 % with the lattice refined on dense frames (fast_cells_per_point) and
// the normals scanning whole windows up to 48 px, on 98.8 % at 4 lattice cells per d_m and 24 px.
TEST(RealData, FullResolutionFrameAgreesWithTheExactPath) {
  UPD_REQUIRE_SHARED_FILE(path, "pcl-data/region_growing_rgb_tutorial.pcd");
  const core::PointCloud cloud = io::readCloud(path);
  core::PipelineParams p;
  p.up = Eigen::Vector3f(0.06f, -0.85f, -0.53f);
  p.preprocess.disableAll();
  p.normals.radius_m = 0.05;
  p.upd.radius_m = 0.5;
  const core::PipelineResult fast = core::runPipeline(cloud, p);
  ASSERT_EQ(fast.method, core::UpdMethod::Fast);
  EXPECT_EQ(fast.fast_cells_per_radius, 8);  // a dense frame: twice fast_cells_per_radius
  const core::Normals normals = core::computeNormals(fast.cloud, core::KdTree(fast.cloud), p.normals, p.unitUp());
  const test::Agreement a =
      test::agreeWithExact(fast.cloud, normals, fast.upd, p.upd, p.unitUp(), 23);
  ASSERT_GT(a.both_valid, 10000u);
  std::printf("region_growing, %zu samples: mean |dzeta| %.5f, same label %.3f %%\n", a.compared,
              a.mean_abs_dzeta, 100 * a.sameLabelFraction());
  EXPECT_LE(a.mean_abs_dzeta, 0.005);
  EXPECT_GE(a.sameLabelFraction(), 0.995);
}

}  // namespace
}  // namespace upd
