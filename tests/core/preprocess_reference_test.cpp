// The pre-processing chain (cut-off, voxel grid, statistical outlier filter) against a plain
// reference written here: a per-point range test, a voxel map in order of first appearance with
// double sums, and a k-d tree's k nearest for the outlier filter. The chain must keep the same
// points with the same centroids: the centroids bit for bit (the sums run over the same points
// in the same order), the mean neighbour distances to float rounding (the chain measures them
// in coordinates relative to an anchor point, the k-d tree in the cloud's), which decides no
// point here (none lies within that rounding of the threshold; checked). On real frames, random
// clouds with NaNs and lone points, organized and not, and tiny and empty clouds; the same
// output for one thread and two (and three, on clouds large enough for the voxel pass to split
// their rows between the threads).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "test_data.h"
#include "upd/core/kdtree.h"
#include "upd/core/preprocess.h"
#ifdef UPD_TEST_HAVE_IO
#include "upd/io/cloud_io.h"
#endif
#ifdef _OPENMP
#include <omp.h>
#endif

namespace upd::core {
namespace {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

// The cut-off of the documentation: the distance from the sensor origin (the difference in
// float, its square in double) within [range_min_m, range_max_m], the box inclusive.
bool refKeeps(const PointCloud& in, std::size_t i, const PreprocessParams& p) {
  if (!in.isFinite(i)) return false;
  const Eigen::Vector3f q = in.point(i);
  if (p.range_enabled) {
    const double d2 = (q - in.sensor_origin).cast<double>().squaredNorm();
    if (!(d2 >= p.range_min_m * p.range_min_m && d2 <= p.range_max_m * p.range_max_m)) return false;
  }
  return !p.box_enabled || ((q.array() >= p.box_min_m.array()).all() &&
                            (q.array() <= p.box_max_m.array()).all());
}

// The voxel grid: voxel floor(d / voxel) per axis of d = point - first kept point (in double,
// d times 1 / voxel), the centroid first kept + (sum of d) / n, in order of first appearance.
PointCloud refVoxels(const PointCloud& in, const std::vector<std::size_t>& kept, double voxel) {
  PointCloud out;
  if (kept.empty()) return out;
  const Eigen::Vector3d ref = in.point(kept.front()).cast<double>();
  const double inv = 1.0 / voxel;
  std::map<std::tuple<double, double, double>, std::size_t> id;
  std::vector<Eigen::Vector3d> sum;
  std::vector<Eigen::Vector3d> rgb;
  std::vector<double> n;
  for (const std::size_t i : kept) {
    const Eigen::Vector3d d = in.point(i).cast<double>() - ref;
    const auto key = std::make_tuple(std::floor(d.x() * inv), std::floor(d.y() * inv),
                                     std::floor(d.z() * inv));
    const auto [it, inserted] = id.emplace(key, sum.size());
    if (inserted) sum.emplace_back(0, 0, 0), rgb.emplace_back(0, 0, 0), n.push_back(0);
    sum[it->second] += d;
    if (in.hasColor()) rgb[it->second] += Eigen::Vector3d(in.r[i], in.g[i], in.b[i]);
    ++n[it->second];
  }
  for (std::size_t v = 0; v < sum.size(); ++v) {
    const Eigen::Vector3d c = ref + sum[v] / n[v];
    const auto avg = [&](double s) { return static_cast<std::uint8_t>(std::lround(s / n[v])); };
    if (in.hasColor()) {
      out.push_back(static_cast<float>(c.x()), static_cast<float>(c.y()),
                    static_cast<float>(c.z()), avg(rgb[v].x()), avg(rgb[v].y()), avg(rgb[v].z()));
    } else {
      out.push_back(static_cast<float>(c.x()), static_cast<float>(c.y()),
                    static_cast<float>(c.z()));
    }
  }
  return out;
}

// The outlier filter by the k-d tree: the mean distance to the k nearest other points, kept
// within mu + alpha sigma. margin: the smallest |mean distance - limit| / limit of any point.
std::vector<char> refOutlierKeep(const PointCloud& c, int k, double alpha, double& margin) {
  std::vector<double> m(c.size(), std::numeric_limits<double>::quiet_NaN());
  const KdTree tree(c);
  std::vector<std::uint32_t> nb;
  std::vector<float> d2;
  double s = 0, s2 = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    tree.knnSearch(c.point(i), k + 1, nb, &d2);
    if (nb.size() < 2) continue;
    double sum = 0;
    for (std::size_t j = 1; j < d2.size(); ++j) sum += std::sqrt(static_cast<double>(d2[j]));
    m[i] = sum / static_cast<double>(d2.size() - 1);
    s += m[i], s2 += m[i] * m[i], ++n;
  }
  std::vector<char> keep(c.size(), 0);
  margin = std::numeric_limits<double>::infinity();
  if (n == 0) return keep;
  const double mu = s / n, limit = mu + alpha * std::sqrt(std::max(0.0, s2 / n - mu * mu));
  for (std::size_t i = 0; i < c.size(); ++i) {
    keep[i] = !std::isnan(m[i]) && m[i] <= limit;
    if (!std::isnan(m[i])) margin = std::min(margin, std::abs(m[i] - limit) / limit);
  }
  return keep;
}

// The whole chain with the voxel grid on (the paper's pipeline), by the reference.
PointCloud refPreprocess(const PointCloud& in, const PreprocessParams& p, double& margin) {
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (refKeeps(in, i, p)) kept.push_back(i);
  }
  const PointCloud voxels = refVoxels(in, kept, p.voxel_m);
  margin = std::numeric_limits<double>::infinity();
  if (!p.outlier_enabled || voxels.empty()) return voxels;
  const std::vector<char> keep = refOutlierKeep(voxels, p.outlier_k, p.outlier_std_mul, margin);
  PointCloud out;
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    if (!keep[i]) continue;
    if (voxels.hasColor()) {
      out.push_back(voxels.x[i], voxels.y[i], voxels.z[i], voxels.r[i], voxels.g[i], voxels.b[i]);
    } else {
      out.push_back(voxels.x[i], voxels.y[i], voxels.z[i]);
    }
  }
  return out;
}

void expectSameCloud(const PointCloud& got, const PointCloud& want) {
  ASSERT_EQ(got.size(), want.size());
  ASSERT_EQ(got.hasColor(), want.hasColor());
  EXPECT_FALSE(got.isOrganized());
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got.x[i], want.x[i]) << "point " << i;
    ASSERT_EQ(got.y[i], want.y[i]) << "point " << i;
    ASSERT_EQ(got.z[i], want.z[i]) << "point " << i;
    if (got.hasColor()) {
      ASSERT_EQ(got.r[i], want.r[i]) << "point " << i;
      ASSERT_EQ(got.g[i], want.g[i]) << "point " << i;
      ASSERT_EQ(got.b[i], want.b[i]) << "point " << i;
    }
  }
}

PreprocessParams paperParams() {
  PreprocessParams p;
  p.range_enabled = true;
  p.range_min_m = 0.4;
  p.range_max_m = 5.0;
  p.voxel_enabled = true;
  p.voxel_m = 0.02;
  p.outlier_enabled = true;
  p.outlier_k = 16;
  p.outlier_std_mul = 2.0;
  return p;
}

void setThreads([[maybe_unused]] int n) {
#ifdef _OPENMP
  omp_set_num_threads(n);
#endif
}

// Both entry points (the returning one and the one into reused buffers, twice), one thread and
// two, against the reference.
void checkChain(const std::string& name, const PointCloud& in, const PreprocessParams& p) {
  SCOPED_TRACE(name);
  double margin = 0;
  const PointCloud want = refPreprocess(in, p, margin);
  EXPECT_GT(margin, 1e-9) << "a point lies within rounding of the outlier threshold";
  PointCloud out;
  for (const int threads : {1, 2}) {
    setThreads(threads);
    SCOPED_TRACE(std::to_string(threads) + " thread(s)");
    PreprocessStats stats;
    expectSameCloud(preprocess(in, p, &stats), want);
    preprocess(in, p, out);
    preprocess(in, p, out);
    expectSameCloud(out, want);
    EXPECT_EQ(stats.points_out, want.size());
    EXPECT_EQ(stats.points_in, in.size());
  }
  setThreads(2);
}

// A surface with noise, NaN holes, lone points and duplicates; organized when width > 0.
PointCloud randomCloud(std::uint32_t seed, std::size_t n, std::size_t width, bool colour) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-2.f, 2.f);
  std::normal_distribution<float> noise(0.f, 0.004f);
  PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    const float x = u(rng), y = u(rng);
    float z = 1.5f + 0.3f * std::sin(2.f * x) * std::cos(1.5f * y) + noise(rng);
    if (i % 101 == 7) z += 0.8f * u(rng);  // lone points off the surface
    const float px = i % 53 == 5 ? kNan : x;
    const auto col = static_cast<std::uint8_t>(i % 251);
    if (colour) {
      c.push_back(px, y, z, col, static_cast<std::uint8_t>(255 - col), 9);
    } else {
      c.push_back(px, y, z);
    }
    if (i % 997 == 11 && i + 1 < n) {  // a duplicate
      c.push_back(c.x.back(), c.y.back(), c.z.back());
      if (colour) c.r.push_back(1), c.g.push_back(2), c.b.push_back(3);
      ++i;
    }
  }
  if (width > 0) c.width = width, c.height = c.size() / width;
  c.sensor_origin = {0.1f, 0.f, -0.2f};
  return c;
}

TEST(PreprocessReference, RandomCloudsKeepTheReferencesPointsAndCentroids) {
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    const bool organized = seed != 2;
    const PointCloud c = randomCloud(seed, 24000, organized ? 200 : 0, seed == 3);
    ASSERT_EQ(c.isOrganized(), organized);
    PreprocessParams p = paperParams();
    p.range_max_m = 2.6;
    p.box_enabled = seed == 3;
    p.box_min_m = {-1.5f, -1.8f, 0.f};
    p.box_max_m = {1.8f, 1.5f, 3.f};
    checkChain("seed " + std::to_string(seed), c, p);
    p.outlier_k = 8, p.outlier_std_mul = 1.0, p.voxel_m = 0.05, p.range_enabled = false;
    checkChain("seed " + std::to_string(seed) + ", k 8, 1 sigma, voxel 0.05, no range", c, p);
  }
}

// The voxel pass's hash map is sized for the voxels of the calls before: clouds of a few hundred
// voxels and of thousands in turn on the same threads (the map grows within a call, and is
// made smaller again after one with far fewer voxels) keep the reference's points and centroids.
TEST(PreprocessReference, VoxelCountsGrowingAndShrinkingCallAfterCall) {
  PreprocessParams p = paperParams();
  p.range_max_m = 2.6;
  std::uint32_t seed = 20;
  for (const std::size_t n : {600u, 12000u, 400u, 12000u, 3000u}) {
    const PointCloud c = randomCloud(seed, n, seed % 2 == 0 ? 200 : 0, true);  // (organized or not)
    ++seed;
    checkChain(std::to_string(n) + " points", c, p);
  }
}

// Holes in runs of every length from 1 to 11 (the voxel pass passes them 4 at a time), at the
// start, inside and at the end of rows: the same points and centroids as the reference.
TEST(PreprocessReference, HoleRunsOfEveryLength) {
  PointCloud c = randomCloud(4, 24000, 200, true);
  std::size_t holes = 0;
  for (std::size_t row = 0; row < c.height; ++row) {
    const std::size_t len = 1 + row % 11;
    const std::size_t at = row % 3 == 0 ? 0 : (row % 3 == 1 ? 97 : c.width - len);
    for (std::size_t col = at; col < at + len; ++col, ++holes) {
      c.x[row * c.width + col] = kNan;
    }
  }
  ASSERT_GT(holes, 700u);
  PreprocessParams p = paperParams();
  p.range_max_m = 2.6;
  checkChain("hole runs", c, p);
}

// A depth camera's frame of w x h pixels (focal length 0.75 w) looking at a tilted, rippled
// surface, 1.5-2.7 m away, with NaN holes: a 2 cm voxel spans several pixels of a row and
// several rows, as on a Kinect frame.
PointCloud depthFrame(std::size_t w, std::size_t h) {
  PointCloud c;
  const float f = 0.75f * static_cast<float>(w);
  for (std::size_t v = 0; v < h; ++v) {
    for (std::size_t u = 0; u < w; ++u) {
      const float du = (static_cast<float>(u) - 0.5f * static_cast<float>(w)) / f;
      const float dv = (static_cast<float>(v) - 0.5f * static_cast<float>(h)) / f;
      const float depth = 1.5f + 1.2f * static_cast<float>(v) / static_cast<float>(h) +
                          0.05f * std::sin(0.05f * static_cast<float>(u));
      const bool hole = (u / 7 + v / 5) % 23 == 0;
      const auto col = static_cast<std::uint8_t>((u + 3 * v) % 256);
      c.push_back(hole ? kNan : du * depth, dv * depth, depth, col, 7, static_cast<std::uint8_t>(v % 256));
    }
  }
  c.width = w, c.height = h;
  c.sensor_origin = {0.f, 0.f, 0.f};
  return c;
}

// From 65,536 points the voxel pass runs on the whole team, each thread summing its share of
// the rows, and from 16,384 centroids so does the compaction after the outlier filter: a depth
// frame (runs along rows and down columns cross the threads' rows) and random clouds, organized
// and not, with colours and without, keep the reference's points and centroids on 1, 2 and 3
// threads.
TEST(PreprocessReference, ATeamSumsTheVoxelsOfLargeCloudsAsOneThread) {
  PreprocessParams p = paperParams();
  const PointCloud frame = depthFrame(400, 200);
  const PointCloud organized = randomCloud(31, 80000, 400, true);
  const PointCloud unorganized = randomCloud(32, 70000, 0, false);
  for (const auto* c : {&frame, &organized, &unorganized}) {
    ASSERT_GT(c->size(), 65536u);
    double margin = 0;
    const PointCloud want = refPreprocess(*c, p, margin);
    ASSERT_GT(want.size(), 1000u);
    // (The random clouds' centroids, with colours and without, are compacted after the outlier
    // filter on the team, from 16,384.)
    if (c != &frame) {
      EXPECT_GT(want.size(), 16384u);
    }
    EXPECT_GT(margin, 1e-9) << "a point lies within rounding of the outlier threshold";
    PointCloud out;
    for (const int threads : {1, 2, 3}) {
      setThreads(threads);
      SCOPED_TRACE(std::to_string(threads) + " thread(s), " + std::to_string(c->size()) +
                   " points" + (c->isOrganized() ? ", organized" : ""));
      preprocess(*c, p, out);
      expectSameCloud(out, want);
    }
  }
  setThreads(2);
}

// The mean distance of every point of c to its k nearest others, each compared with every point
// in double (the k-d tree computes in float from its own origin: on a cloud spanning hundreds of
// metres it is off by 1e-4 relative).
std::vector<double> bruteMeans(const PointCloud& c, int k) {
  std::vector<double> m(c.size(), std::numeric_limits<double>::quiet_NaN()), d;
  const std::size_t finite = c.countFinite();
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!c.isFinite(i)) continue;  // (NaN: not scored)
    d.clear();
    for (std::size_t j = 0; j < c.size(); ++j) {
      if (c.isFinite(j)) d.push_back((c.point(i).cast<double>() - c.point(j).cast<double>()).norm());
    }
    const auto kk = static_cast<std::size_t>(std::min<std::size_t>(k, finite - 1));
    if (kk == 0) continue;
    std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(kk), d.end());
    double sum = 0;
    for (std::size_t j = 0; j <= kk; ++j) sum += d[j];  // (d[0 .. kk]: the point itself at 0)
    m[i] = sum / static_cast<double>(kk);
  }
  return m;
}

// meanNeighbourDistances against every point compared with every point, call after call into the
// same buffer (the search keeps its buffers from call to call): a surface with a strip a tenth as
// dense (settled by the block of cells around a point's own, or by the wider block and the third
// ring), the same with a wall of mixed density, 200 lone points scattered far apart (beyond the
// rings: the k-d tree), 40 lone points (compared with every point), a cloud with NaN points
// among the others (NaN for them, the others' neighbours among the finite points), for several
// k, on one thread and two, and a larger cloud after a smaller one and back. (The grid's cells are looked up in
// its dense table, or by the hash where far lone points leave the box too sparse for one: with
// the lone points, both, depending on k.)
TEST(PreprocessReference, MeanNeighbourDistancesAreTheNearestCallAfterCall) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  PointCloud surface;
  for (int i = 0; i < 2500; ++i) {
    const float x = 2.f * u(rng), y = 2.f * u(rng);
    if (x > 0.9f && x < 1.1f && u(rng) > 0.1f) continue;
    surface.push_back(x, y, 0.01f * std::sin(5.f * x));
  }
  PointCloud mixed = surface;
  for (int i = 0; i < 700; ++i) mixed.push_back(2.f, 2.f * u(rng), 0.6f * u(rng) * u(rng));
  PointCloud many_lone = surface, few_lone = surface;
  for (int i = 0; i < 200; ++i) many_lone.push_back(10.f + 3.f * i, -5.f - 2.f * i, 4.f);
  for (int i = 0; i < 40; ++i) few_lone.push_back(-10.f - 3.f * i, 7.f, -3.f + 0.5f * i);
  PointCloud holes = mixed;  // (the non-finite points are left out of the grid)
  for (std::size_t i = 3; i < holes.size(); i += 7) holes.x[i] = std::numeric_limits<float>::quiet_NaN();
  const std::vector<const PointCloud*> clouds = {&surface, &mixed, &many_lone, &few_lone, &holes};
  const std::vector<int> ks = {4, 16, 40};
  std::vector<std::vector<double>> want;  // per cloud and k
  for (const PointCloud* c : clouds) {
    for (const int k : ks) want.push_back(bruteMeans(*c, k));
  }
  std::vector<double> got;
  for (const int threads : {1, 2}) {
    setThreads(threads);
    for (const std::size_t ci : {0u, 1u, 2u, 3u, 4u, 0u, 1u}) {
      for (std::size_t ki = 0; ki < ks.size(); ++ki) {
        SCOPED_TRACE(std::to_string(threads) + " thread(s), cloud " + std::to_string(ci) +
                     ", k " + std::to_string(ks[ki]));
        meanNeighbourDistances(*clouds[ci], ks[ki], got);
        const std::vector<double>& w = want[ci * ks.size() + ki];
        ASSERT_EQ(got.size(), w.size());
        for (std::size_t i = 0; i < w.size(); ++i) {
          if (std::isnan(w[i])) {
            ASSERT_TRUE(std::isnan(got[i])) << "point " << i;
            continue;
          }
          ASSERT_NEAR(got[i], w[i], 1e-5 * w[i]) << "point " << i;  // (float rounding)
        }
      }
    }
  }
  setThreads(2);
}

TEST(PreprocessReference, TinyAndEmptyClouds) {
  PreprocessParams p = paperParams();
  p.range_enabled = false;
  checkChain("empty", PointCloud{}, p);
  PointCloud nan_only;
  for (int i = 0; i < 5; ++i) nan_only.push_back(kNan, 0.f, 1.f);
  checkChain("NaN only", nan_only, p);
  PointCloud one;
  one.push_back(1.f, 2.f, 3.f);
  checkChain("1 point", one, p);
  for (const std::size_t n : {3u, 17u, 40u}) {
    checkChain(std::to_string(n) + " points", randomCloud(9, n, 0, false), p);
  }
  PointCloud all_cut = randomCloud(4, 500, 0, false);
  p.range_enabled = true, p.range_min_m = 50, p.range_max_m = 60;
  checkChain("everything cut", all_cut, p);
}

TEST(PreprocessReference, RealFramesKeepTheReferencesPointsAndCentroids) {
#ifndef UPD_TEST_HAVE_IO
  GTEST_SKIP() << "built without libs/io (UPD_CORE_ONLY): no PCD reader; skipped";
#else
  for (const char* rel : {"pcl/office1.pcd", "pcl-data/region_growing_rgb_tutorial.pcd"}) {
    UPD_REQUIRE_SHARED_FILE(path, rel);
    const PointCloud frame = io::readCloud(path);
    ASSERT_TRUE(frame.isOrganized());
    checkChain(rel, frame, paperParams());
  }
#endif
}

}  // namespace
}  // namespace upd::core
