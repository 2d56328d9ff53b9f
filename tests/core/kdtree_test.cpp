// The k-d tree equals a brute-force scan for radius and k-nearest queries.
#include "synthetic.h"
#include "upd/core/kdtree.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace upd::core {
namespace {

std::vector<std::uint32_t> bruteRadius(const PointCloud& c, const Eigen::Vector3f& q, float r) {
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (c.isFinite(i) && (c.point(i) - q).squaredNorm() <= r * r) out.push_back(i);
  }
  return out;
}

TEST(KdTree, RadiusSearchEqualsBruteForce) {
  PointCloud c = test::makeRandomCloud(5000, 7);
  c.x[10] = std::numeric_limits<float>::quiet_NaN();  // never indexed
  const KdTree tree(c);
  EXPECT_EQ(tree.indexedCount(), 4999u);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-2.5f, 2.5f);
  std::vector<std::uint32_t> got;
  for (int t = 0; t < 200; ++t) {
    const Eigen::Vector3f q(u(rng), u(rng), 0.1f * u(rng));
    const float r = 0.05f + 0.5f * std::abs(u(rng));
    tree.radiusSearch(q, r, got);
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, bruteRadius(c, q, r)) << "query " << t;
  }
}

TEST(KdTree, KnnEqualsBruteForceDistances) {
  const PointCloud c = test::makeRandomCloud(3000, 11);
  const KdTree tree(c);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-2.f, 2.f);
  std::vector<std::uint32_t> got;
  std::vector<float> d2;
  for (int t = 0; t < 100; ++t) {
    const Eigen::Vector3f q(u(rng), u(rng), 0.f);
    const int k = 1 + t % 40;
    tree.knnSearch(q, k, got, &d2);
    std::vector<float> all;
    for (std::size_t i = 0; i < c.size(); ++i) all.push_back((c.point(i) - q).squaredNorm());
    std::sort(all.begin(), all.end());
    ASSERT_EQ(got.size(), static_cast<std::size_t>(k));
    for (int j = 0; j < k; ++j) {
      // The tree measures in its own centred frame: equal up to float rounding.
      EXPECT_NEAR(d2[j], all[j], 1e-5f * (1.f + all[j]));
      EXPECT_NEAR((c.point(got[j]) - q).squaredNorm(), all[j], 1e-5f * (1.f + all[j]));
    }
  }
}

TEST(KdTree, FewerPointsThanKAndEmptyCloud) {
  PointCloud c;
  c.push_back(0, 0, 0);
  c.push_back(1, 0, 0);
  const KdTree tree(c);
  std::vector<std::uint32_t> got;
  tree.knnSearch(Eigen::Vector3f::Zero(), 5, got);
  EXPECT_EQ(got.size(), 2u);
  const PointCloud empty;
  const KdTree t2(empty);
  t2.radiusSearch(Eigen::Vector3f::Zero(), 1.f, got);
  EXPECT_TRUE(got.empty());
  t2.knnSearch(Eigen::Vector3f::Zero(), 3, got);
  EXPECT_TRUE(got.empty());
}

TEST(KdTree, DuplicatePointsAndFarFromOrigin) {
  PointCloud c;
  for (int i = 0; i < 100; ++i) c.push_back(10000.f, 10000.f, 10000.f);  // all equal
  for (int i = 0; i < 50; ++i) c.push_back(10000.f + 0.01f * i, 10000.f, 10000.f);
  const KdTree tree(c);
  std::vector<std::uint32_t> got;
  tree.radiusSearch(Eigen::Vector3f(10000.f, 10000.f, 10000.f), 0.0f, got);
  EXPECT_EQ(got.size(), 101u);  // 100 duplicates + the first of the line
  tree.radiusSearch(Eigen::Vector3f(10000.f, 10000.f, 10000.f), 0.1f, got);
  std::sort(got.begin(), got.end());
  EXPECT_EQ(got, bruteRadius(c, Eigen::Vector3f(10000.f, 10000.f, 10000.f), 0.1f));
}

}  // namespace
}  // namespace upd::core
