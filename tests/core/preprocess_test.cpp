// Pre-processing (paper section 3): voxel down-sampling keeps one centroid per voxel, the
// statistical outlier removal drops isolated points, the whole chain keeps what it should.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "synthetic.h"
#include "upd/core/kdtree.h"
#include "upd/core/preprocess.h"
#include "upd/sim/scenes.h"

namespace upd::core {
namespace {

using namespace upd::sim;  // generated scenes as test inputs

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

TEST(PointCloud, CountFiniteCountsPointsWithThreeFiniteCoordinates) {
  const float inf = std::numeric_limits<float>::infinity();
  const float big = std::numeric_limits<float>::max();
  PointCloud c;
  c.push_back(0.f, 0.f, 0.f);      // finite
  c.push_back(big, -big, 1e-38f);  // finite, at the ends of the range
  c.push_back(inf, 0.f, 0.f);
  c.push_back(0.f, -inf, 0.f);
  c.push_back(0.f, 0.f, kNan);
  c.push_back(-0.f, 5.f, -3.f);                                  // finite
  for (int i = 0; i < 37; ++i) c.push_back(1.f * i, kNan, 2.f);  // past any vector width
  c.push_back(1.f, 2.f, 3.f);                                    // finite
  EXPECT_EQ(c.countFinite(), 4u);
  std::size_t by_point = 0;
  for (std::size_t i = 0; i < c.size(); ++i) by_point += c.isFinite(i) ? 1 : 0;
  EXPECT_EQ(by_point, 4u);
}

TEST(PointCloud, ResizeKeepsThePointsAndGivesOrDropsTheColour) {
  PointCloud c;
  c.push_back(1.f, 2.f, 3.f, 10, 20, 30);
  c.push_back(4.f, 5.f, 6.f, 40, 50, 60);
  c.resize(3, true);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_TRUE(c.hasColor());
  EXPECT_EQ(c.point(1), Eigen::Vector3f(4.f, 5.f, 6.f));
  EXPECT_EQ(c.g[1], 50);
  EXPECT_EQ(c.width, 2u) << "the layout is the caller's";
  c.resize(1, false);
  EXPECT_EQ(c.size(), 1u);
  EXPECT_FALSE(c.hasColor());
  EXPECT_TRUE(c.r.empty() && c.g.empty() && c.b.empty());
  EXPECT_EQ(c.point(0), Eigen::Vector3f(1.f, 2.f, 3.f));
}

TEST(Preprocess, VoxelGridKeepsTheCentroidOfEachVoxelInOrderOfFirstAppearance) {
  PointCloud c;
  // Voxel edge 1, anchored at the first point: two points in voxel (0, 0, 0), one in
  // (2, 0, 0), two in (0, 1, 0), with a NaN point between them and the voxels revisited out of
  // order.
  c.push_back(0.f, 0.f, 0.f, 10, 20, 30);
  c.push_back(2.5f, 0.5f, 0.5f, 0, 0, 0);
  c.push_back(0.4f, 1.5f, 0.1f, 100, 100, 100);
  c.push_back(kNan, kNan, kNan, 1, 1, 1);
  c.push_back(0.6f, 0.4f, 0.8f, 30, 40, 50);
  c.push_back(0.6f, 1.7f, 0.3f, 200, 200, 200);
  const PointCloud v = voxelDownsample(c, 1.0);
  ASSERT_EQ(v.size(), 3u);
  ASSERT_TRUE(v.hasColor());
  EXPECT_NEAR(v.x[0], 0.3f, 1e-6f);  // voxel (0, 0, 0), first seen first
  EXPECT_NEAR(v.y[0], 0.2f, 1e-6f);
  EXPECT_NEAR(v.z[0], 0.4f, 1e-6f);
  EXPECT_EQ(v.r[0], 20);
  EXPECT_EQ(v.g[0], 30);
  EXPECT_EQ(v.b[0], 40);
  EXPECT_NEAR(v.x[1], 2.5f, 1e-6f);  // voxel (2, 0, 0)
  EXPECT_NEAR(v.x[2], 0.5f, 1e-6f);  // voxel (0, 1, 0)
  EXPECT_NEAR(v.y[2], 1.6f, 1e-6f);
  EXPECT_NEAR(v.z[2], 0.2f, 1e-6f);
  EXPECT_EQ(v.r[2], 150);
}

TEST(Preprocess, VoxelGridIsTheSameFarFromTheOrigin) {
  // A 1 m x 1 m plane sampled every 1/128 m, at the origin and 8 km away (UTM-like; the
  // coordinates stay exact floats): the same voxels, the same centroids relative to the cloud.
  PointCloud near_origin, far;
  const float shift = 8192.f;
  for (int i = 0; i < 128; ++i) {
    for (int k = 0; k < 128; ++k) {
      const float x = static_cast<float>(i) / 128.f, y = static_cast<float>(k) / 128.f;
      near_origin.push_back(x, y, 0.25f * x);
      far.push_back(x + shift, y - shift, 0.25f * x + shift);
    }
  }
  const PointCloud a = voxelDownsample(near_origin, 0.02);
  const PointCloud b = voxelDownsample(far, 0.02);
  ASSERT_GT(a.size(), 2000u);
  ASSERT_EQ(b.size(), a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_NEAR(b.x[i] - shift, a.x[i], 1e-3f);  // 1e-3: the float spacing at 8 km
    EXPECT_NEAR(b.y[i] + shift, a.y[i], 1e-3f);
    EXPECT_NEAR(b.z[i] - shift, a.z[i], 1e-3f);
  }
}

TEST(Preprocess, StatisticalOutliersAreIsolatedPoints) {
  // A dense plane and three points 0.5 m above it: only those three are dropped.
  PointCloud c;
  for (int i = 0; i < 50; ++i) {
    for (int k = 0; k < 50; ++k) {
      c.push_back(0.01f * static_cast<float>(i), 0.01f * static_cast<float>(k), 0.f);
    }
  }
  c.push_back(0.1f, 0.1f, 0.5f);
  c.push_back(0.3f, 0.2f, 0.6f);
  c.push_back(0.4f, 0.4f, -0.5f);
  const PointCloud kept = removeStatisticalOutliers(c, 8, 1.0);
  ASSERT_EQ(kept.size(), 2500u);
  for (std::size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(kept.z[i], 0.f);
}

// The outlier filter's mean neighbour distances from the grid equal the k-d tree's: on a
// voxelized scene, a random volume, a cloud with lone points far off, duplicates, and clouds
// with fewer points than k + 1.
TEST(Preprocess, MeanNeighbourDistancesEqualTheKdTrees) {
  const auto kdTreeMeans = [](const PointCloud& c, int k) {
    std::vector<double> m(c.size(), std::numeric_limits<double>::quiet_NaN());
    const KdTree tree(c);
    std::vector<std::uint32_t> nb;
    std::vector<float> d2;
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (!c.isFinite(i)) continue;
      tree.knnSearch(c.point(i), k + 1, nb, &d2);
      if (nb.size() < 2) continue;
      double s = 0;
      for (std::size_t j = 1; j < d2.size(); ++j) s += std::sqrt(static_cast<double>(d2[j]));
      m[i] = s / static_cast<double>(d2.size() - 1);
    }
    return m;
  };
  std::vector<std::pair<std::string, PointCloud>> clouds;
  clouds.emplace_back("rocks voxelized", voxelDownsample(makeScene("rocks").cloud, 0.02));
  clouds.emplace_back("random volume", test::makeRandomCloud(3000, 3, 1.f));
  PointCloud lone = makeScene("step").cloud;
  lone.push_back(5.f, 5.f, 5.f);
  lone.push_back(-3.f, 0.f, 2.f);
  lone.push_back(kNan, 0.f, 0.f);
  for (int i = 0; i < 40; ++i) lone.push_back(lone.x[7], lone.y[7], lone.z[7]);  // duplicates
  clouds.emplace_back("lone points and duplicates", lone);
  PointCloud few;
  for (int i = 0; i < 5; ++i) few.push_back(0.1f * static_cast<float>(i), 0.f, 0.f);
  clouds.emplace_back("5 points", few);
  PointCloud one;
  one.push_back(1.f, 2.f, 3.f);
  clouds.emplace_back("1 point", one);
  for (const auto& [name, c] : clouds) {
    for (const int k : {1, 8, 16, 130}) {  // (130: beyond the grid's array, the k-d tree)
      SCOPED_TRACE(name + ", k " + std::to_string(k));
      const std::vector<double> grid = meanNeighbourDistances(c, k);
      const std::vector<double> tree = kdTreeMeans(c, k);
      ASSERT_EQ(grid.size(), c.size());
      for (std::size_t i = 0; i < c.size(); ++i) {
        ASSERT_EQ(std::isnan(grid[i]), std::isnan(tree[i])) << "point " << i;
        if (std::isnan(tree[i])) continue;
        ASSERT_NEAR(grid[i], tree[i], 1e-6 * (1.0 + tree[i])) << "point " << i;
      }
    }
  }
}

TEST(Preprocess, WithEveryStepOffTheInputComesBackUnchanged) {
  PointCloud c;
  c.resizeOrganized(4, 3);
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (i == 5) continue;  // stays NaN
    c.x[i] = static_cast<float>(i), c.y[i] = 1.f, c.z[i] = 2.f;
  }
  PreprocessParams p;
  p.disableAll();
  PreprocessStats stats;
  PointCloud out;
  out.push_back(9.f, 9.f, 9.f);  // reused buffers: overwritten, not appended to
  preprocess(c, p, out, &stats);
  ASSERT_EQ(out.size(), c.size());
  EXPECT_TRUE(out.isOrganized());
  EXPECT_TRUE(std::isnan(out.x[5]));
  EXPECT_EQ(out.x[7], 7.f);
  EXPECT_EQ(stats.points_in, 12u);
  EXPECT_EQ(stats.non_finite, 1u);
  EXPECT_EQ(stats.points_out, 12u);
}

// A sensor-rate config (range cut and box only) on an organized frame runs in the caller's
// buffers; it must give what the copying path gives, point for point, stats included.
TEST(Preprocess, RangeCutIntoReusedBuffersEqualsTheCopyingPath) {
  PointCloud c;
  c.resizeOrganized(400, 200);  // over the size that runs in parallel
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (i % 97 == 3) continue;  // stays NaN
    const float t = 0.001f * static_cast<float>(i);
    c.x[i] = std::sin(t) * 3.f, c.y[i] = std::cos(1.3f * t) * 2.f, c.z[i] = 0.5f + 0.07f * t;
  }
  c.x[10] = std::numeric_limits<float>::infinity();
  c.sensor_origin = {0.1f, -0.2f, 0.3f};
  c.r.resize(c.size()), c.g.resize(c.size()), c.b.resize(c.size());
  for (std::size_t i = 0; i < c.size(); ++i) {
    c.r[i] = static_cast<std::uint8_t>(i), c.g[i] = static_cast<std::uint8_t>(i / 3), c.b[i] = 5;
  }
  for (const bool box : {false, true}) {
    PreprocessParams p;
    p.disableAll();
    p.range_enabled = true;
    p.range_min_m = 0.7;
    p.range_max_m = 3.0;
    p.box_enabled = box;
    p.box_min_m = {-2.f, -1.5f, -1.f};
    p.box_max_m = {2.5f, 1.5f, 4.f};
    PreprocessStats expected_stats, stats;
    const PointCloud expected = preprocess(c, p, &expected_stats);
    PointCloud out;
    preprocess(c, p, out, &stats);  // twice: the second run reuses the first one's buffers
    preprocess(c, p, out, &stats);
    ASSERT_EQ(out.size(), expected.size()) << "box " << box;
    EXPECT_EQ(out.width, expected.width);
    EXPECT_EQ(out.height, expected.height);
    EXPECT_EQ(out.sensor_origin, expected.sensor_origin);
    EXPECT_TRUE(out.r == expected.r && out.g == expected.g && out.b == expected.b);
    std::size_t removed = 0;
    for (std::size_t i = 0; i < out.size(); ++i) {
      const bool nan_expected = std::isnan(expected.x[i]);
      ASSERT_EQ(std::isnan(out.x[i]), nan_expected) << "point " << i << ", box " << box;
      if (!nan_expected) {
        ASSERT_EQ(out.x[i], expected.x[i]);
        ASSERT_EQ(out.y[i], expected.y[i]);
        ASSERT_EQ(out.z[i], expected.z[i]);
      }
      removed += nan_expected && c.isFinite(i) ? 1 : 0;
    }
    EXPECT_GT(removed, 1000u) << "the cut must remove points for the test to mean anything";
    EXPECT_EQ(stats.points_in, expected_stats.points_in);
    EXPECT_EQ(stats.non_finite, expected_stats.non_finite);
    EXPECT_EQ(stats.range_removed, expected_stats.range_removed);
    EXPECT_EQ(stats.after_voxel, expected_stats.after_voxel);
    EXPECT_EQ(stats.outliers_removed, expected_stats.outliers_removed);
    EXPECT_EQ(stats.points_out, expected_stats.points_out);
  }
}

}  // namespace
}  // namespace upd::core

namespace upd::core {
namespace {

// transformCloud, transformInPlace and rotateVectors equal Eigen's per-point products; NaN
// stays NaN; the layout, the colour and the sensor origin follow.
TEST(PointCloud, TransformAndRotateEqualEigenPerPoint) {
  PointCloud c;
  for (int i = 0; i < 70000; ++i) {  // over the size that runs in parallel
    c.push_back(0.001f * i, std::sin(0.01f * i), 2.f - 0.0005f * i, i % 256, 7, 9);
  }
  c.x[5] = std::numeric_limits<float>::quiet_NaN();
  c.width = 700, c.height = 100;
  c.sensor_origin = {0.1f, 0.2f, 0.3f};
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  t.translation() = Eigen::Vector3d(100.0, -5.0, 2.5);
  PointCloud out;
  out.x.assign(3, 42.f);  // stale contents are replaced
  transformCloud(c, t, out);
  ASSERT_EQ(out.size(), c.size());
  EXPECT_EQ(out.width, 700u);
  EXPECT_EQ(out.height, 100u);
  EXPECT_EQ(out.r, c.r);
  EXPECT_TRUE(std::isnan(out.x[5]) && std::isnan(out.y[5]) && std::isnan(out.z[5]));
  const Eigen::Matrix3f r = t.linear().cast<float>();
  const Eigen::Vector3f tr = t.translation().cast<float>();
  for (std::size_t i = 0; i < c.size(); i += 997) {
    if (i == 5) continue;
    EXPECT_TRUE(out.point(i).isApprox(r * c.point(i) + tr, 1e-5f)) << i;
  }
  EXPECT_TRUE(out.sensor_origin.isApprox(r * c.sensor_origin + tr, 1e-6f));
  EXPECT_THROW(transformCloud(c, t, c), std::invalid_argument);

  PointCloud moved = c;
  transformInPlace(moved, t);
  const std::size_t bytes = c.size() * sizeof(float);  // the same products, in place
  EXPECT_EQ(std::memcmp(moved.x.data(), out.x.data(), bytes), 0);
  EXPECT_EQ(std::memcmp(moved.y.data(), out.y.data(), bytes), 0);
  EXPECT_EQ(std::memcmp(moved.z.data(), out.z.data(), bytes), 0);
  EXPECT_EQ(moved.r, c.r);
  EXPECT_EQ(moved.sensor_origin, out.sensor_origin);

  std::vector<float> vx = c.x, vy = c.y, vz = c.z;
  rotateVectors(r, c.size(), vx.data(), vy.data(), vz.data());
  EXPECT_TRUE(std::isnan(vx[5]));
  for (std::size_t i = 1; i < c.size(); i += 1009) {
    EXPECT_TRUE(Eigen::Vector3f(vx[i], vy[i], vz[i]).isApprox(r * c.point(i), 1e-5f)) << i;
  }
}

}  // namespace
}  // namespace upd::core
