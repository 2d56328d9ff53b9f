// The learned-classifier hook of the pipeline: a labeler replaces the rule's labels of the
// scored points, leaves the unscored ones Unknown, and recounts.
#include "upd/core/pipeline.h"
#include "upd/core/point_labeler.h"

#include "upd/sim/scenes.h"

#include <gtest/gtest.h>

namespace upd::core {
namespace {

// Non-traversable exactly where x > 0 (the step's upper side), whatever the geometry.
class HalfPlaneLabeler : public PointLabeler {
 public:
  const FeatureParams& featureParams() const override { return params_; }
  std::vector<float> probabilityOfFeatures(const std::vector<float>&) const override { return {}; }
  std::vector<float> probability(const PointCloud& cloud, const Normals&,
                                 const Eigen::Vector3f&) const override {
    std::vector<float> p(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) p[i] = cloud.x[i] > 0 ? 0.9f : 0.1f;
    return p;
  }

 private:
  FeatureParams params_;
};

TEST(PointLabeler, ReplacesTheRuleOnScoredPointsOnly) {
  sim::SceneParams sp;
  sp.spacing_m = 0.05;
  const sim::Scene s = sim::makeScene("step", sp);
  PipelineParams p;
  p.preprocess.disableAll();
  const PipelineResult rule = runPipeline(s.cloud, p);
  const HalfPlaneLabeler labeler;
  Classification c = rule.classes;
  applyPointLabeler(labeler, rule.cloud, rule.normals, p.unitUp(), c);
  std::size_t trav = 0, non = 0;
  for (std::size_t i = 0; i < c.label.size(); ++i) {
    if (rule.classes.label[i] == Label::Unknown) {
      EXPECT_EQ(c.label[i], Label::Unknown);
      continue;
    }
    const bool upper = rule.cloud.x[i] > 0;
    EXPECT_EQ(c.label[i], upper ? Label::NonTraversable : Label::Traversable) << i;
    EXPECT_FLOAT_EQ(c.cost[i], upper ? 1.f : 0.1f);
    ++(upper ? non : trav);
  }
  EXPECT_EQ(c.traversable, trav);
  EXPECT_EQ(c.non_traversable, non);
  EXPECT_EQ(c.unknown, rule.classes.unknown);
  EXPECT_GT(trav, 100u);
  EXPECT_GT(non, 100u);
}

TEST(PointLabeler, NoLoaderRegisteredIsAnError) {
  setPointLabelerLoader(nullptr);
  try {
    loadPointLabeler("model.yml");
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("model.yml"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace upd::core
