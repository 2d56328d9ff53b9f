// Bad parameters are rejected with a message naming the field and the value; degenerate inputs
// (empty, fewer than 3 points, all NaN) give a well-defined result instead of a crash.
#include "upd/core/pipeline.h"
#include "error_of.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iterator>

namespace upd::core {
namespace {

std::string errorOf(const PipelineParams& p) {
  return upd::test::errorOf<std::invalid_argument>([&] { p.validate(); });
}

TEST(Params, DefaultsAreValid) { EXPECT_EQ(errorOf(PipelineParams{}), ""); }

TEST(Params, NegativeRadiusNamesFieldAndValue) {
  PipelineParams p;
  p.upd.radius_m = -1;
  EXPECT_EQ(errorOf(p), "UpdParams.radius_m = -1: must be > 0");
}

TEST(Params, ZeroVoxelNamesFieldAndValue) {
  PipelineParams p;
  p.preprocess.voxel_m = 0;
  EXPECT_EQ(errorOf(p), "PreprocessParams.voxel_m = 0: must be > 0");
}

TEST(Params, ZeroUpVectorNamesFieldAndValue) {
  PipelineParams p;
  p.up = Eigen::Vector3f::Zero();
  EXPECT_EQ(errorOf(p), "PipelineParams.up = 0,0,0: must be a non-zero finite vector");
}

TEST(Params, OtherRulesNameTheirField) {
  PipelineParams p;
  p.normals.radius_m = std::nan("");
  EXPECT_NE(errorOf(p).find("NormalParams.radius_m = nan"), std::string::npos);
  p = {};
  p.classify.zeta_caution = 0.5;
  EXPECT_NE(errorOf(p).find("ClassifyParams.zeta_caution = 0.5"), std::string::npos);
  p = {};
  p.classify.max_slope_rad = 100 * kDegToRad;
  EXPECT_NE(errorOf(p).find("ClassifyParams.max_slope_deg = 100"), std::string::npos);
  p = {};
  p.preprocess.range_max_m = -2;
  EXPECT_NE(errorOf(p).find("PreprocessParams.range_max_m = -2"), std::string::npos);
  p = {};
  p.upd.knn = 2;
  EXPECT_NE(errorOf(p).find("UpdParams.knn = 2"), std::string::npos);
}

// Enum fields hold the enum; each has one table of ini names, one name per value.
TEST(Params, EnumNameTablesCoverEveryValueOnce) {
  EXPECT_STREQ(enumName(kUpdMethodNames, UpdMethod::Auto), "auto");
  EXPECT_STREQ(enumName(kUpdMethodNames, UpdMethod::Exact), "exact");
  EXPECT_STREQ(enumName(kUpdMethodNames, UpdMethod::Fast), "fast");
  EXPECT_EQ(enumName(kUpdMethodNames, static_cast<UpdMethod>(3)), nullptr);
  EXPECT_EQ(enumNameList(kUpdMethodNames), "auto|exact|fast");
  EXPECT_STREQ(enumName(kNormalWeightingNames, NormalWeighting::Uniform), "uniform");
  EXPECT_STREQ(enumName(kNormalWeightingNames, NormalWeighting::Gaussian), "gaussian");
  EXPECT_EQ(enumNameList(kNormalWeightingNames), "uniform|gaussian");
  // The old numbers of user configs are the enums' values.
  for (std::size_t i = 0; i < std::size(kUpdMethodNames); ++i) {
    EXPECT_EQ(static_cast<std::size_t>(kUpdMethodNames[i].value), i);
  }
  EXPECT_EQ(UpdParams{}.method, UpdMethod::Auto);
  EXPECT_EQ(NormalParams{}.weighting, NormalWeighting::Uniform);
}

TEST(Params, EnumOutOfRangeNamesFieldAndValue) {
  PipelineParams p;
  p.upd.method = static_cast<UpdMethod>(7);
  EXPECT_EQ(errorOf(p), "UpdParams.method = 7: must be auto, exact or fast");
  p = {};
  p.normals.weighting = static_cast<NormalWeighting>(-1);
  EXPECT_EQ(errorOf(p), "NormalParams.weighting = -1: must be uniform or gaussian");
  p = {};
  p.upd.method = UpdMethod::Fast;
  p.normals.knn = 16;
  EXPECT_NE(errorOf(p).find("UpdParams.method = fast"), std::string::npos) << errorOf(p);
}

TEST(Params, RunPipelineRejectsBadParameters) {
  PipelineParams p;
  p.upd.radius_m = 0;
  PointCloud c;
  c.push_back(0, 0, 0);
  EXPECT_THROW(runPipeline(c, p), std::invalid_argument);
}

TEST(DegenerateInput, EmptyCloudGivesEmptyResult) {
  const PipelineResult r = runPipeline(PointCloud{}, PipelineParams{});
  EXPECT_EQ(r.cloud.size(), 0u);
  EXPECT_EQ(r.upd.size(), 0u);
  EXPECT_EQ(r.classes.traversable + r.classes.non_traversable + r.classes.unknown, 0u);
}

TEST(DegenerateInput, FewerThanThreePointsAreUnknown) {
  PointCloud c;
  c.push_back(0, 0, 0);
  c.push_back(0.01f, 0, 0);
  PipelineParams p;
  p.preprocess.disableAll();
  const PipelineResult r = runPipeline(c, p);
  ASSERT_EQ(r.upd.size(), 2u);
  EXPECT_EQ(r.normals.invalid, 2u);
  EXPECT_EQ(r.upd.invalid, 2u);
  EXPECT_EQ(r.classes.unknown, 2u);
  EXPECT_TRUE(std::isnan(r.classes.cost[0]));
}

TEST(DegenerateInput, AllNaNOrganizedCloudKeepsLayoutAndCountsEveryPoint) {
  PointCloud c;
  c.resizeOrganized(8, 6);
  PipelineParams p;
  p.preprocess.disableAll();
  const PipelineResult r = runPipeline(c, p);
  EXPECT_TRUE(r.cloud.isOrganized());
  EXPECT_EQ(r.upd.invalid, 48u);
  EXPECT_EQ(r.classes.unknown, 48u);
  // With pre-processing on, the NaNs are dropped and counted as non-finite.
  const PipelineResult r2 = runPipeline(c, PipelineParams{});
  EXPECT_EQ(r2.cloud.size(), 0u);
  EXPECT_EQ(r2.preprocess_stats.non_finite, 48u);
}

}  // namespace
}  // namespace upd::core
