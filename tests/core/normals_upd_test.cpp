// Normals (eqs. 4-5) and the UPD (eqs. 6-8): equal to a brute-force reference, and the
// properties the method promises (planes of any slope give zeta = 1, slope = tilt, invariance to
// rotations about up and to translations far from the origin, NaN for too few neighbours).
#include "synthetic.h"
#include "upd/core/classify.h"
#include "upd/core/normals.h"
#include "upd/core/pipeline.h"
#include "upd/sim/scenes.h"
#include "upd/core/upd.h"

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace upd::core {
namespace {

using namespace upd::sim;  // generated scenes as test inputs

const Eigen::Vector3f kUp = Eigen::Vector3f::UnitZ();

// Brute-force neighbourhood: a linear scan.
std::vector<std::uint32_t> scan(const PointCloud& c, std::size_t i, float r) {
  std::vector<std::uint32_t> out;
  for (std::size_t j = 0; j < c.size(); ++j) {
    if ((c.point(j) - c.point(i)).squaredNorm() <= r * r) out.push_back(j);
  }
  return out;
}

TEST(Normals, EqualBruteForcePca) {
  const PointCloud c = test::makeRandomCloud(1500, 21, 1.f);
  const KdTree tree(c);
  NormalParams p;
  p.radius_m = 0.15;
  const Normals n = computeNormals(c, tree, p, kUp);
  for (std::size_t i = 0; i < c.size(); i += 7) {
    const auto nb = scan(c, i, 0.15f);
    if (nb.size() < 3) {
      EXPECT_FALSE(n.isValid(i));
      continue;
    }
    // Reference: textbook covariance about the centroid, smallest eigenvector, up-oriented.
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (auto j : nb) mean += c.point(j).cast<double>();
    mean /= nb.size();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (auto j : nb) {
      const Eigen::Vector3d d = c.point(j).cast<double>() - mean;
      cov += d * d.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov / nb.size());
    const Eigen::Vector3f ref = es.eigenvectors().col(0).cast<float>();
    ASSERT_TRUE(n.isValid(i));
    // Same axis; the sign is the orientation rule's, checked separately below.
    EXPECT_NEAR(std::abs(n.normal(i).dot(ref)), 1.f, 1e-4f) << "point " << i;
    const Eigen::Vector3f oriented =
        orientNormal(ref, c.point(i), c.sensor_origin, kUp, p.vertical_band_rad);
    EXPECT_GT(n.normal(i).dot(oriented), 0.f) << "point " << i;
  }
}

TEST(Normals, FewerThanThreeNeighboursGiveNaNAndAreCounted) {
  PointCloud c;
  c.push_back(0, 0, 0);
  c.push_back(0.01f, 0, 0);
  c.push_back(5, 5, 5);  // isolated
  c.push_back(std::nanf(""), 0, 0);
  const KdTree tree(c);
  const Normals n = computeNormals(c, tree, NormalParams{}, kUp);
  EXPECT_EQ(n.invalid, 4u);
  for (std::size_t i = 0; i < c.size(); ++i) EXPECT_FALSE(n.isValid(i));
}

TEST(Normals, CollinearNeighbourhoodIsInvalid) {
  PointCloud c;
  for (int i = 0; i < 20; ++i) c.push_back(0.005f * i, 0, 0);
  const KdTree tree(c);
  const Normals n = computeNormals(c, tree, NormalParams{}, kUp);
  EXPECT_EQ(n.invalid, c.size());
}

TEST(Normals, OrientedUpAndWallsTowardsTheSensor) {
  // A horizontal plane seen from below still gets normals pointing up.
  PointCloud floor = test::makePlane(0.5, 0.02);
  floor.sensor_origin = Eigen::Vector3f(0, 0, -3);
  const KdTree t1(floor);
  const Normals n1 = computeNormals(floor, t1, NormalParams{}, kUp);
  for (std::size_t i = 0; i < floor.size(); ++i) EXPECT_GT(n1.nz[i], 0.99f);
  // A vertical wall x = 0 seen from +x: every normal points to +x.
  Eigen::Isometry3d wall_pose = Eigen::Isometry3d::Identity();
  wall_pose.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  PointCloud wall = test::makePlane(0.5, 0.02, wall_pose);
  wall.sensor_origin = Eigen::Vector3f(2, 0.1f, 0.3f);
  const KdTree t2(wall);
  const Normals n2 = computeNormals(wall, t2, NormalParams{}, kUp);
  for (std::size_t i = 0; i < wall.size(); ++i) EXPECT_GT(n2.nx[i], 0.99f);
  wall.sensor_origin = Eigen::Vector3f(-2, 0.1f, 0.3f);
  const Normals n3 = computeNormals(wall, t2, NormalParams{}, kUp);
  for (std::size_t i = 0; i < wall.size(); ++i) EXPECT_LT(n3.nx[i], -0.99f);
}

TEST(Normals, GaussianWeightsKeepPlanesExact) {
  const PointCloud c = test::makePlane(0.6, 0.02);
  const KdTree tree(c);
  NormalParams p;
  p.weighting = NormalWeighting::Gaussian;
  const Normals n = computeNormals(c, tree, p, kUp);
  EXPECT_EQ(n.invalid, 0u);
  for (std::size_t i = 0; i < c.size(); ++i) EXPECT_NEAR(n.nz[i], 1.f, 1e-5f);
}

TEST(Upd, EqualsBruteForceSum) {
  const PointCloud c = test::makeRandomCloud(2000, 33, 1.f);
  const KdTree tree(c);
  NormalParams np;
  np.radius_m = 0.12;
  const Normals n = computeNormals(c, tree, np, kUp);
  UpdParams up;
  up.radius_m = 0.3;
  const UpdResult u = computeUpd(c, tree, n, up);
  for (std::size_t i = 0; i < c.size(); i += 5) {
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    std::uint32_t k = 0;
    for (auto j : scan(c, i, 0.3f)) {
      if (!n.isValid(j)) continue;
      r += n.normal(j).cast<double>();
      ++k;
    }
    if (k < 3) {
      EXPECT_FALSE(u.isValid(i));
      continue;
    }
    EXPECT_EQ(u.k[i], k);
    EXPECT_NEAR(u.rx[i], r.x(), 1e-3);
    EXPECT_NEAR(u.ry[i], r.y(), 1e-3);
    EXPECT_NEAR(u.rz[i], r.z(), 1e-3);
    EXPECT_NEAR(u.zeta[i], r.norm() / k, 1e-5);
  }
}

TEST(Upd, KnnNeighbourhoodUsesExactlyKPoints) {
  const PointCloud c = test::makeRandomCloud(800, 8, 1.f);
  const KdTree tree(c);
  const Normals n = computeNormals(c, tree, NormalParams{}, kUp);
  UpdParams p;
  p.knn = 25;
  const UpdResult u = computeUpd(c, tree, n, p);
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (u.isValid(i)) {
      EXPECT_LE(u.k[i], 25u);
    }
  }
}

// A plane of any tilt: zeta = 1 everywhere, and the classified slope equals the tilt.
class TiltedPlane : public ::testing::TestWithParam<double> {};

TEST_P(TiltedPlane, ZetaIsOneAndSlopeEqualsTilt) {
  const double tilt = GetParam() * kDegToRad;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  const PointCloud c = test::makePlane(1.6, 0.02, pose);
  PipelineParams p;
  p.preprocess.disableAll();
  const PipelineResult res = runPipeline(c, p);
  std::size_t checked = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    ASSERT_TRUE(res.upd.isValid(i));
    EXPECT_NEAR(res.upd.zeta[i], 1.0, 1e-4);
    EXPECT_NEAR(res.classes.slope_rad[i], tilt, 2e-3);
    ++checked;
  }
  EXPECT_EQ(checked, c.size());
}

INSTANTIATE_TEST_SUITE_P(Tilts, TiltedPlane, ::testing::Values(0.0, 5.0, 20.0, 35.0, 60.0));

// The label counts are those of the labels written, and each label follows the rule: unknown
// where zeta is NaN or k < min_neighbors, else non-traversable where zeta < zeta_min or the slope
// of r exceeds max_slope. Over several of the stage's chunks, with NaN, vanishing r and k at the
// bound; fixed seed.
TEST(Classify, LabelsFollowTheRuleAndTheCountsAreTheLabelsWritten) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-1.f, 1.f), zeta(0.9f, 1.f);
  const std::size_t n = 30011;
  UpdResult r = UpdResult::unscored(n);
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 13 == 0) continue;  // unscored
    r.rx[i] = u(rng), r.ry[i] = u(rng), r.rz[i] = 2.f + u(rng);
    if (i % 17 == 0) r.rx[i] = r.ry[i] = r.rz[i] = 0.f;  // no direction: the steepest slope
    r.zeta[i] = zeta(rng);
    r.k[i] = static_cast<std::uint32_t>(8 + i % 5);  // below, at and over min_neighbors
  }
  ClassifyParams p;
  p.min_neighbors = 10;
  const Classification c = classify(r, kUp, p);
  ASSERT_EQ(c.label.size(), n);
  std::size_t counts[3] = {0, 0, 0};
  for (std::size_t i = 0; i < n; ++i) {
    const bool valid = !std::isnan(r.zeta[i]) && r.k[i] >= 10;
    const Eigen::Vector3f v(r.rx[i], r.ry[i], r.rz[i]);
    const double slope = v.squaredNorm() > 0 ? std::acos(v.normalized().dot(kUp)) : M_PI;
    if (std::abs(slope - p.max_slope_rad) > 1e-5) {  // (acos to 2e-7 rad)
      const Label want = !valid ? Label::Unknown
                         : r.zeta[i] < p.zeta_min || slope > p.max_slope_rad
                             ? Label::NonTraversable
                             : Label::Traversable;
      ASSERT_EQ(c.label[i], want) << "point " << i;
    }
    ++counts[static_cast<int>(c.label[i])];
  }
  EXPECT_EQ(c.traversable, counts[static_cast<int>(Label::Traversable)]);
  EXPECT_EQ(c.non_traversable, counts[static_cast<int>(Label::NonTraversable)]);
  EXPECT_EQ(c.unknown, counts[static_cast<int>(Label::Unknown)]);
  EXPECT_GT(c.traversable, 1000u);
  EXPECT_GT(c.non_traversable, 1000u);
  EXPECT_GT(c.unknown, 1000u);
}

// Results compared point by point: zeta, k and labels.
struct Diff {
  double max_dzeta = 0, mean_dzeta = 0;
  std::size_t k_diff = 0, label_diff = 0;
};
Diff compare(const PipelineResult& a, const PipelineResult& b) {
  Diff d;
  EXPECT_EQ(a.upd.size(), b.upd.size());
  for (std::size_t i = 0; i < a.upd.size(); ++i) {
    EXPECT_EQ(a.upd.isValid(i), b.upd.isValid(i));
    if (!a.upd.isValid(i) || !b.upd.isValid(i)) continue;
    const double dz = std::abs(a.upd.zeta[i] - b.upd.zeta[i]);
    d.max_dzeta = std::max(d.max_dzeta, dz);
    d.mean_dzeta += dz / a.upd.size();
    d.k_diff += a.upd.k[i] != b.upd.k[i];
    d.label_diff += a.classes.label[i] != b.classes.label[i];
  }
  return d;
}

PipelineParams noPreprocess(double radius_m) {
  PipelineParams p;
  p.preprocess.disableAll();
  p.upd.radius_m = radius_m;
  p.upd.method = UpdMethod::Exact;  // the exact path's invariances
  return p;
}

// Coordinates on a 2^-10 m grid stay exact when moved by +10 km (float ulp there is 2^-10), so
// the translated cloud is the same cloud: any difference is the algorithm's own rounding.
TEST(Upd, TranslationFarFromOriginChangesNothing) {
  PointCloud c = test::makeRandomCloud(4000, 99, 1.5f);
  for (auto* v : {&c.x, &c.y, &c.z}) {
    for (float& f : *v) f = std::round(f * 1024.f) / 1024.f;
  }
  c.sensor_origin = Eigen::Vector3f(0, 0, 3);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(10240.0, -10240.0, 10240.0);
  const auto p = noPreprocess(0.4);
  const Diff d = compare(runPipeline(c, p), runPipeline(test::transformed(c, T), p));
  EXPECT_LT(d.max_dzeta, 1e-5);
  EXPECT_EQ(d.k_diff, 0u);
  EXPECT_EQ(d.label_diff, 0u);
}

TEST(Upd, RotationAboutUpChangesNothing) {
  // Rough ground with rocks: normals of every direction, steep flanks included.
  SceneParams sp;
  sp.spacing_m = 0.03;
  const Scene s = makeScene("rocks", sp);
  const auto p = noPreprocess(0.5);
  const PipelineResult a = runPipeline(s.cloud, p);
  for (const double yaw : {0.3, 2.0, -1.1}) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Diff d = compare(a, runPipeline(test::transformed(s.cloud, T), p));
    // Rotation rounds coordinates by ~1e-7 m: only a neighbour exactly on a sphere may flip.
    EXPECT_LT(d.mean_dzeta, 1e-5) << "yaw " << yaw;
    EXPECT_LT(d.max_dzeta, 1e-3) << "yaw " << yaw;
    EXPECT_LE(d.k_diff, s.cloud.size() / 100) << "yaw " << yaw;
    EXPECT_LE(d.label_diff, s.cloud.size() / 1000) << "yaw " << yaw;
  }
}

}  // namespace
}  // namespace upd::core
