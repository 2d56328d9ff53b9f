// The classifier's features on scenes with known geometry: a tilted plane, the step.
#include "upd/core/point_features.h"

#include "upd/sim/scenes.h"

#include <gtest/gtest.h>

#include <cmath>

namespace upd::core {
namespace {

PointCloud tiltedPlane(double tilt_rad) {
  PointCloud c;
  for (int i = 0; i <= 60; ++i) {
    for (int j = 0; j <= 60; ++j) {
      const float x = -1.5f + 0.05f * i, y = -1.5f + 0.05f * j;
      c.push_back(x, y, static_cast<float>(std::tan(tilt_rad) * x));
    }
  }
  c.sensor_origin = {0, 0, 5};
  return c;
}

Normals normalsOf(const PointCloud& c) {
  NormalParams p;
  p.radius_m = 0.12;
  return computeNormals(c, KdTree(c), p, Eigen::Vector3f::UnitZ());
}

TEST(PointFeatures, TiltedPlaneIsSmoothAndSlopedEverywhere) {
  const double tilt = 15.0 * kDegToRad;
  const PointCloud c = tiltedPlane(tilt);
  const FeatureParams fp;
  const std::vector<float> f = computeFeatures(c, normalsOf(c), Eigen::Vector3f::UnitZ(), fp);
  ASSERT_EQ(f.size(), c.size() * kFeatureCount);
  const std::size_t centre = 30 * 61 + 30;  // (0, 0): every radius fits inside the plane
  const float* row = &f[centre * kFeatureCount];
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(row[4 * j + 0], 1.0, 1e-4) << kFeatureNames[4 * j];      // zeta
    EXPECT_NEAR(row[4 * j + 1], tilt, 1e-3) << kFeatureNames[4 * j + 1];  // slope of r
    EXPECT_NEAR(row[4 * j + 3], tilt, 1e-3) << kFeatureNames[4 * j + 3];  // inclination
    EXPECT_GT(row[4 * j + 2], 0.0) << "a tilted plane is 'rough' to the roughness index";
  }
  EXPECT_NEAR(row[12], tilt, 1e-3);                                   // normal slope
  EXPECT_NEAR(row[13], std::tan(tilt) * 0.45, 0.03);                  // height range of a cell
  EXPECT_NEAR(row[15], 1.0 / (0.05 * 0.05), 0.15 / (0.05 * 0.05));    // density [1/m^2]
  EXPECT_NEAR(row[16], 5.0, 1e-4);                                    // range to the sensor
}

TEST(PointFeatures, StepCellsSpanTheRiserAndMissingIsMinusOne) {
  sim::SceneParams sp;
  sp.spacing_m = 0.05;
  sim::Scene s = sim::makeScene("step", sp);
  for (float& x : s.cloud.x) x += 0.2f;  // the riser (x = 0) mid-cell, not on a cell border
  std::vector<float> range, spread;
  columnHeightStats(s.cloud, s.up, 0.5, range, spread);
  float highest = 0;
  for (float r : range) highest = std::max(highest, r);
  EXPECT_NEAR(highest, sim::scene_geometry::kStepHeight_m, 1e-3);

  PointCloud lone = tiltedPlane(0);
  lone.push_back(50, 50, 0);  // alone: no neighbours, no normal
  const std::vector<float> f =
      computeFeatures(lone, normalsOf(lone), Eigen::Vector3f::UnitZ(), FeatureParams{});
  const float* row = &f[(lone.size() - 1) * kFeatureCount];
  for (int j = 0; j < 12; ++j) EXPECT_EQ(row[j], -1.f) << kFeatureNames[j];
  EXPECT_EQ(row[12], -1.f);
  EXPECT_EQ(row[13], 0.f);  // its own cell
}

TEST(PointFeatures, BadParamsNameTheField) {
  FeatureParams p;
  p.radius_small_m = 0.8;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = FeatureParams{};
  p.cell_m = 0;
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace upd::core
