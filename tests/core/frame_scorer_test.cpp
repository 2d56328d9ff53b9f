// The per-frame scorer: a cloud in its own frame + its pose in, scored points in the world out.
#include "upd/core/frame_scorer.h"

#include "synthetic.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace core = upd::core;

namespace {

using upd::core::FrameScorer;
using upd::core::FrameScorerParams;
using upd::core::Label;
using upd::core::ObstacleDetector;
using upd::core::PointCloud;
using upd::core::ScoredFrame;

constexpr double kDeg = M_PI / 180.0;

Eigen::Isometry3d pose(double x, double y, double z, double yaw, double pitch = 0.0) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translate(Eigen::Vector3d(x, y, z));
  t.rotate(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  t.rotate(Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()));
  return t;
}

// A floor with a 0.3 m step up across it at x = 0.3 m, riser included: traversable and
// non-traversable points.
core::PointCloud floorWithStep() {
  core::PointCloud c = upd::test::makePlane(3.0, 0.04);
  const std::size_t floor_points = c.size();
  for (std::size_t i = 0; i < floor_points; ++i) {
    if (c.x[i] > 0.3f) c.z[i] += 0.3f;
  }
  for (int j = 0; j <= 75; ++j) {
    for (int k = 1; k < 8; ++k) c.push_back(0.3f, -1.5f + 0.04f * j, 0.04f * k);
  }
  return c;
}

bool sameOrBothNaN(float a, float b) { return a == b || (std::isnan(a) && std::isnan(b)); }

TEST(FrameScorer, DetectorNamesParse) {
  EXPECT_EQ(upd::core::parseObstacleDetector("upd"), core::ObstacleDetector::Upd);
  EXPECT_EQ(upd::core::parseObstacleDetector("roughness"), core::ObstacleDetector::Roughness);
  EXPECT_STREQ(upd::core::toString(core::ObstacleDetector::Roughness), "roughness");
  EXPECT_THROW(upd::core::parseObstacleDetector("lidar"), std::invalid_argument);
}

TEST(FrameScorer, UpMustBeTheWorldsZ) {
  core::FrameScorerParams p;
  p.pipeline.up = Eigen::Vector3f(0, 1, 0);
  EXPECT_THROW(core::FrameScorer{p}, std::invalid_argument);
}

TEST(FrameScorer, EmptyCloudGivesAnEmptyFrame) {
  const core::ScoredFrame f = core::FrameScorer().score(core::PointCloud{}, pose(1, 2, 0, 0.5));
  EXPECT_EQ(f.size(), 0u);
  EXPECT_TRUE(f.classes.label.empty());
  EXPECT_TRUE(f.obstacles_world.empty());
}

// A frame loop passes one ScoredFrame: from the third frame on, a frame of the same size
// allocates no new storage for the results.
TEST(FrameScorer, FramesOfTheSameSizeReuseTheBuffersFromTheThird) {
  core::FrameScorerParams p;
  p.pipeline.preprocess.disableAll();
  p.obstacles_xy = true;
  const core::FrameScorer scorer(p);
  const core::PointCloud cloud = floorWithStep();
  for (const Eigen::Isometry3d& t : {pose(3, -2, 0.1, 0.7), Eigen::Isometry3d::Identity()}) {
    core::ScoredFrame f;
    scorer.score(cloud, t, f);
    ASSERT_EQ(f.size(), cloud.size());
    ASSERT_GT(f.obstacles_world.size(), 0u);
    const float* x = f.cloud_world.x.data();
    const float* nx = f.normals_world.nx.data();
    const float* rz = f.upd.rz.data();
    const float* zeta = f.upd.zeta.data();
    const core::Label* label = f.classes.label.data();
    const float* cost = f.classes.cost.data();
    const auto* obstacles = f.obstacles_world.data();
    // (The results and the scratch trade their buffers every frame: the third frame's are the
    // first's.)
    scorer.score(cloud, t, f);
    scorer.score(cloud, t, f);
    EXPECT_EQ(f.cloud_world.x.data(), x);
    EXPECT_EQ(f.normals_world.nx.data(), nx);
    EXPECT_EQ(f.upd.rz.data(), rz);
    EXPECT_EQ(f.upd.zeta.data(), zeta);
    EXPECT_EQ(f.classes.label.data(), label);
    EXPECT_EQ(f.classes.cost.data(), cost);
    EXPECT_EQ(f.obstacles_world.data(), obstacles);
  }
}

// The world output is the cloud-frame scoring (gravity from the pose) moved by the pose.
TEST(FrameScorer, WorldOutputIsTheCloudFrameScoringMovedByThePose) {
  const core::FrameScorerParams p;
  const Eigen::Isometry3d t = pose(12.0, -3.0, 0.25, 30 * kDeg, 8 * kDeg);
  const core::PointCloud cloud = floorWithStep();
  const core::ScoredFrame f = core::FrameScorer(p).score(cloud, t);

  upd::core::PipelineParams in_cloud = p.pipeline;
  in_cloud.up = (t.linear().transpose() * Eigen::Vector3d::UnitZ()).cast<float>();
  const upd::core::PipelineResult ref = upd::core::runPipeline(cloud, in_cloud);
  ASSERT_EQ(f.size(), ref.cloud.size());
  ASSERT_GT(f.size(), 1000u);
  EXPECT_EQ(f.classes.label, ref.classes.label);
  EXPECT_GT(f.classes.non_traversable, 0u);
  EXPECT_GT(f.classes.traversable, 0u);
  const Eigen::Matrix3f r = t.linear().cast<float>();
  for (std::size_t i = 0; i < f.size(); ++i) {
    const Eigen::Vector3d moved = t * ref.cloud.point(i).cast<double>();
    ASSERT_LT((moved - f.cloud_world.point(i).cast<double>()).norm(), 1e-4);
    ASSERT_TRUE(sameOrBothNaN(f.upd.zeta[i], ref.upd.zeta[i]));
    ASSERT_TRUE(sameOrBothNaN(f.classes.slope_rad[i], ref.classes.slope_rad[i]));
    if (ref.upd.isValid(i)) {
      ASSERT_TRUE((r * ref.upd.r(i)).isApprox(f.upd.r(i), 1e-5f));
    }
    if (ref.normals.isValid(i)) {
      ASSERT_TRUE((r * ref.normals.normal(i)).isApprox(f.normals_world.normal(i), 1e-5f));
    }
  }
  EXPECT_TRUE(f.cloud_world.sensor_origin.isApprox(
      (t * cloud.sensor_origin.cast<double>()).cast<float>(), 1e-5f));
}

// Turning the cloud's frame about gravity and moving it far away changes no label.
TEST(FrameScorer, PoseAboutGravityAndFarAwayChangesNoLabel) {
  for (const core::ObstacleDetector d : {core::ObstacleDetector::Upd, core::ObstacleDetector::Roughness}) {
    core::FrameScorerParams p;
    p.detector = d;
    const core::FrameScorer scorer(p);
    const core::PointCloud cloud = floorWithStep();
    const core::ScoredFrame a = scorer.score(cloud, Eigen::Isometry3d::Identity());
    const core::ScoredFrame b = scorer.score(cloud, pose(5000.0, -7000.0, 40.0, 2.5));
    ASSERT_EQ(a.size(), b.size()) << upd::core::toString(d);
    EXPECT_EQ(a.classes.label, b.classes.label) << upd::core::toString(d);
    EXPECT_GT(a.classes.non_traversable, 0u) << upd::core::toString(d);
  }
}

double nonTraversableFraction(const core::ScoredFrame& f) {
  return static_cast<double>(f.classes.non_traversable) / static_cast<double>(f.size());
}

// Paper section 5: the roughness index reads a smooth 20 deg ramp as an obstacle, the UPD
// does not.
TEST(FrameScorer, RoughnessFlagsA20DegRampTheUpdDoesNot) {
  const Eigen::Isometry3d tilt(Eigen::AngleAxisd(20 * kDeg, Eigen::Vector3d::UnitX()));
  const core::PointCloud ramp = upd::test::makePlane(4.0, 0.04, tilt);
  core::FrameScorerParams p;
  const core::ScoredFrame by_upd = core::FrameScorer(p).score(ramp, Eigen::Isometry3d::Identity());
  p.detector = core::ObstacleDetector::Roughness;
  p.obstacles_xy = true;
  const core::ScoredFrame by_roughness = core::FrameScorer(p).score(ramp, Eigen::Isometry3d::Identity());
  EXPECT_LT(nonTraversableFraction(by_upd), 0.05);
  EXPECT_GT(nonTraversableFraction(by_roughness), 0.5);
  EXPECT_EQ(by_roughness.obstacles_world.size(), by_roughness.classes.non_traversable);
  EXPECT_TRUE(by_roughness.upd.zeta.empty());
}

// The same ramp seen flat from a frame pitched 20 deg: gravity comes from the pose, so the
// slope is 20 deg and the roughness index flags it too.
TEST(FrameScorer, GravityComesFromThePose) {
  const core::PointCloud flat = upd::test::makePlane(4.0, 0.04);
  const Eigen::Isometry3d pitched = pose(0, 0, 0, 0, 20 * kDeg);
  core::FrameScorerParams p;
  const core::ScoredFrame f = core::FrameScorer(p).score(flat, pitched);
  std::vector<float> slopes;
  for (const float s : f.classes.slope_rad) {
    if (std::isfinite(s)) slopes.push_back(s);
  }
  ASSERT_FALSE(slopes.empty());
  std::nth_element(slopes.begin(), slopes.begin() + slopes.size() / 2, slopes.end());
  EXPECT_NEAR(slopes[slopes.size() / 2], 20 * kDeg, 1 * kDeg);
  p.detector = core::ObstacleDetector::Roughness;
  EXPECT_GT(nonTraversableFraction(core::FrameScorer(p).score(flat, pitched)), 0.5);
  EXPECT_LT(nonTraversableFraction(core::FrameScorer(p).score(flat, Eigen::Isometry3d::Identity())),
            0.05);
}

}  // namespace
