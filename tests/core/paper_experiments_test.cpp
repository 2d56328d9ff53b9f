// The paper's simulated experiments (Bellone & Reina 2013, section 6), reproduced on the
// generated scenes: the 90 deg corner and the 20 deg ramp with the roughness-index contrast.
#include "upd/core/baselines.h"
#include "upd/core/pipeline.h"
#include "upd/sim/scenes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace upd::core {
namespace {

using namespace upd::sim;  // generated scenes as test inputs

constexpr double kHalfSqrt2 = 0.70710678118654752;
// With a 0.01 m grid, a 0.015 m radius takes the 3 x 3 pixel block: the normals' own support is
// this narrow, so the UPD's band around an edge is d_m wide plus this.
constexpr double kCornerNormalRadius_m = 0.015;

PipelineResult scoreScene(const Scene& s, double d_m, double normal_radius_m) {
  PipelineParams p;
  p.preprocess.disableAll();
  p.up = s.up;
  p.upd.radius_m = d_m;
  p.normals.radius_m = normal_radius_m;
  p.upd.method = UpdMethod::Exact;  // the paper's experiments: exact sums
  return runPipeline(s.cloud, p);
}

// Distance of a corner point to the edge (the y axis): floor points have z = 0, wall x = 0.
double edgeDistance(const PointCloud& c, std::size_t i) { return std::hypot(c.x[i], c.z[i]); }

class Corner : public ::testing::TestWithParam<double> {};

TEST_P(Corner, ZetaIsOneOnBothPlanesAwayFromTheEdgeAndAtLeastHalfSqrt2Everywhere) {
  const double d_m = GetParam();
  const Scene s = makeScene("corner");
  const PipelineResult r = scoreScene(s, d_m, kCornerNormalRadius_m);
  std::size_t far_floor = 0, far_wall = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    ASSERT_TRUE(r.upd.isValid(i)) << "point " << i;
    EXPECT_GE(r.upd.zeta[i], kHalfSqrt2 - 0.01) << "point " << i;
    if (edgeDistance(s.cloud, i) > d_m + kCornerNormalRadius_m) {
      EXPECT_NEAR(r.upd.zeta[i], 1.0, 1e-5) << "point " << i;
      (s.cloud.z[i] == 0.f ? far_floor : far_wall)++;
    }
  }
  if (d_m < 0.9) {  // at d_m = 1 m no point of a 1 m plane is farther than d_m from the edge
    EXPECT_GT(far_floor, 100u);
    EXPECT_GT(far_wall, 100u);
  }
}

TEST_P(Corner, MinimumZetaLiesOnTheEdgeAndIsNearHalfSqrt2) {
  const double d_m = GetParam();
  const Scene s = makeScene("corner");
  const PipelineResult r = scoreScene(s, d_m, kCornerNormalRadius_m);
  std::size_t arg_min = 0;
  for (std::size_t i = 1; i < s.cloud.size(); ++i) {
    if (r.upd.zeta[i] < r.upd.zeta[arg_min]) arg_min = i;
  }
  EXPECT_LE(edgeDistance(s.cloud, arg_min), 0.011) << "minimum at point " << arg_min;
  EXPECT_NEAR(r.upd.zeta[arg_min], kHalfSqrt2, 0.03);
}

INSTANTIATE_TEST_SUITE_P(SearchRadii, Corner, ::testing::Values(0.1, 0.5, 1.0));

// The width of the band where zeta < 1 grows with d_m (it is about d_m + the normal radius).
TEST(CornerBand, WidensWithTheSearchRadius) {
  const Scene s = makeScene("corner");
  double previous = 0;
  for (const double d_m : {0.1, 0.5, 1.0}) {
    const PipelineResult r = scoreScene(s, d_m, kCornerNormalRadius_m);
    double width = 0;
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
      if (r.upd.zeta[i] < 0.9999) width = std::max(width, edgeDistance(s.cloud, i));
    }
    EXPECT_GT(width, previous) << "d_m = " << d_m;
    EXPECT_NEAR(width, std::min(d_m + kCornerNormalRadius_m, std::sqrt(2.0)), 0.03)
        << "d_m = " << d_m;
    previous = width;
  }
}

// The ramp scene: ground z = 0, a 20 deg ramp from x = 0 to x = 2 (|y| <= 0.75), a platform.
class Ramp : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SceneParams sp;
    sp.spacing_m = 0.02;
    scene_ = new Scene(makeScene("ramp", sp));
    result_ = new PipelineResult(scoreScene(*scene_, kDm, 0.1));
  }
  static void TearDownTestSuite() {
    delete scene_;
    delete result_;
  }
  static constexpr double kDm = 0.5;
  static constexpr double kClear = kDm + 0.1;  // d_m plus the normal radius
  static bool onRampBody(const PointCloud& c, std::size_t i) {
    return c.x[i] > kClear && c.x[i] < 2.0 - kClear && std::abs(c.y[i]) < 0.75 - kClear;
  }
  static bool onOpenGround(const PointCloud& c, std::size_t i) {
    return c.x[i] < -kClear && c.z[i] < 1e-3 && std::abs(c.y[i]) < 1.5 - 0.01;
  }
  static bool onLowerBorder(const PointCloud& c, std::size_t i) {
    return std::abs(c.x[i]) < 0.1 && std::abs(c.y[i]) < 0.75 - kClear;
  }
  static Scene* scene_;
  static PipelineResult* result_;
};
Scene* Ramp::scene_ = nullptr;
PipelineResult* Ramp::result_ = nullptr;

TEST_F(Ramp, RampBodyZetaMatchesTheGroundAndBothAreTraversable) {
  const PointCloud& c = scene_->cloud;
  std::size_t body = 0, ground = 0;
  double zeta_body = 0, zeta_ground = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const bool is_body = onRampBody(c, i), is_ground = onOpenGround(c, i);
    if (!is_body && !is_ground) continue;
    EXPECT_EQ(result_->classes.label[i], Label::Traversable) << "point " << i;
    if (is_body) {
      zeta_body += result_->upd.zeta[i];
      ++body;
      EXPECT_NEAR(result_->classes.slope_rad[i], 20.0 * kDegToRad, 1e-3);
    } else {
      zeta_ground += result_->upd.zeta[i];
      ++ground;
    }
  }
  ASSERT_GT(body, 200u);
  ASSERT_GT(ground, 200u);
  EXPECT_NEAR(zeta_body / body, zeta_ground / ground, 1e-4);
  EXPECT_NEAR(zeta_body / body, 1.0, 1e-4);
}

TEST_F(Ramp, LowerBorderIsFlaggedButStaysTraversable) {
  const PointCloud& c = scene_->cloud;
  const ClassifyParams defaults;
  std::size_t border = 0, flagged = 0, traversable = 0;
  double min_zeta = 1;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!onLowerBorder(c, i)) continue;
    ++border;
    min_zeta = std::min(min_zeta, double(result_->upd.zeta[i]));
    flagged += result_->upd.zeta[i] < defaults.zeta_caution && result_->classes.cost[i] > 0.f;
    traversable += result_->classes.label[i] == Label::Traversable;
  }
  ASSERT_GT(border, 100u);
  EXPECT_GE(double(flagged) / border, 0.9);
  EXPECT_EQ(traversable, border);  // a 20 deg concave border: Dune climbs it
  // Two planes at 20 deg, half and half: zeta = cos(10 deg).
  EXPECT_NEAR(min_zeta, std::cos(10.0 * kDegToRad), 0.005);
}

TEST_F(Ramp, RoughnessIndexFlagsTheSmoothRampBodyButNotTheGround) {
  const PointCloud& c = scene_->cloud;
  const KdTree tree(c);
  BaselineParams bp;
  bp.radius_m = kDm;
  const BaselineResult b = computeBaselines(c, tree, scene_->up, bp);
  std::size_t body = 0, body_flagged = 0, ground = 0, ground_flagged = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (onRampBody(c, i)) {
      ++body;
      body_flagged += b.roughness_label[i] == Label::NonTraversable;
      // A plane tilted by a over a disc of radius d: sigma = tan(a) cos(a) d / 2.
      EXPECT_NEAR(b.roughness_m[i], std::sin(20.0 * kDegToRad) * kDm / 2, 0.01);
      EXPECT_NEAR(b.inclination_rad[i], 20.0 * kDegToRad, 1e-3);
    } else if (onOpenGround(c, i)) {
      ++ground;
      ground_flagged += b.roughness_label[i] == Label::NonTraversable;
    }
  }
  EXPECT_EQ(body_flagged, body);  // the paper's Fig. 5: the baseline blocks the ramp
  EXPECT_EQ(ground_flagged, 0u);
}

// Steps, stairs, the ditch and rocks: their borders are non-traversable for the UPD.
class Obstacles : public ::testing::TestWithParam<const char*> {};

TEST_P(Obstacles, TruthObstaclesAreFoundAndOpenGroundIsFree) {
  SceneParams sp;
  sp.spacing_m = 0.02;
  const Scene s = makeScene(GetParam(), sp);
  const PipelineResult r = scoreScene(s, 0.5, 0.1);
  std::size_t truth_obstacle = 0, found = 0, truth_free = 0, free_ok = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    if (s.truth[i] == Label::NonTraversable) {
      ++truth_obstacle;
      found += r.classes.label[i] == Label::NonTraversable;
    } else if (s.truth[i] == Label::Traversable) {
      ++truth_free;
      free_ok += r.classes.label[i] == Label::Traversable;
    }
  }
  ASSERT_GT(truth_obstacle, 0u);
  ASSERT_GT(truth_free, 0u);
  // The UPD band is d_m wide, wider than the truth band: every obstacle point is found, and
  // some free ground near obstacles is given up (the price of a robot-sized d_m).
  EXPECT_GE(double(found) / truth_obstacle, 0.95) << GetParam();
  EXPECT_GE(double(free_ok) / truth_free, 0.4) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Scenes, Obstacles,
                         ::testing::Values("step", "stairs", "ditch", "rocks"));

}  // namespace
}  // namespace upd::core
