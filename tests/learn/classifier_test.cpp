// The learned classifier: it learns a separable rule, its file round-trips, bad files fail
// with one line naming the file.
#include "upd/learn/classifier.h"

#include "temp_dir.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

namespace upd::learn {
namespace {

using core::kFeatureCount;
using core::Label;

// Points whose zeta (feature 0) is below 0.9 or whose slope (feature 1) is above 0.5 are
// obstacles; the other features are noise.
void makeData(int n, int seed, std::vector<float>& f, std::vector<Label>& t) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  f.resize(std::size_t(n) * kFeatureCount);
  t.resize(n);
  for (int i = 0; i < n; ++i) {
    float* row = &f[std::size_t(i) * kFeatureCount];
    for (int j = 0; j < kFeatureCount; ++j) row[j] = u(rng);
    row[0] = 0.7f + 0.3f * u(rng);
    t[i] = row[0] < 0.9f || row[1] > 0.5f ? Label::NonTraversable : Label::Traversable;
  }
}

double accuracy(const PointClassifier& c, const std::vector<float>& f, const std::vector<Label>& t) {
  const std::vector<float> p = c.probabilityOfFeatures(f);
  int right = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    EXPECT_GE(p[i], 0.f);
    EXPECT_LE(p[i], 1.f);
    right += (p[i] >= 0.5f) == (t[i] == Label::NonTraversable);
  }
  return double(right) / t.size();
}

TEST(PointClassifier, EveryKindLearnsASeparableRule) {
  std::vector<float> f, g;
  std::vector<Label> t, u;
  makeData(3000, 1, f, t);
  makeData(1000, 2, g, u);
  for (ModelKind kind : {ModelKind::RandomTrees, ModelKind::Boost, ModelKind::Svm}) {
    TrainParams p;
    p.kind = kind;
    p.trees = 30;
    const auto c = PointClassifier::train(f, t, core::FeatureParams{}, p);
    EXPECT_GT(accuracy(*c, g, u), 0.93) << toString(kind);
  }
}

TEST(PointClassifier, FileRoundTripsAndBadFilesFail) {
  std::vector<float> f;
  std::vector<Label> t;
  makeData(800, 3, f, t);
  TrainParams p;
  p.trees = 10;
  core::FeatureParams fp;
  fp.radius_m = 0.6;
  const auto c = PointClassifier::train(f, t, fp, p);
  const test::TempDir tmp;
  const std::string path = (tmp.path() / "m.yml").string();
  c->save(path);
  const auto back = PointClassifier::load(path);
  EXPECT_EQ(back->kind(), ModelKind::RandomTrees);
  EXPECT_EQ(back->featureParams().radius_m, 0.6);
  EXPECT_EQ(back->probabilityOfFeatures(f), c->probabilityOfFeatures(f));
  EXPECT_EQ(c->featureImportance().size(), std::size_t(kFeatureCount));

  const std::string gz = (tmp.path() / "m.yml.gz").string();  // compressed, as shipped
  c->save(gz);
  EXPECT_EQ(PointClassifier::load(gz)->probabilityOfFeatures(f), c->probabilityOfFeatures(f));

  registerLoader();
  EXPECT_NE(core::loadPointLabeler(path), nullptr);
  const std::string junk = (tmp.path() / "junk.yml").string();
  std::ofstream(junk) << "%YAML:1.0\nfoo: 1\n";
  const auto expectOneLine = [](const std::string& file, const std::string& part) {
    try {
      PointClassifier::load(file);
      FAIL() << file;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  };
  expectOneLine(junk, "not an UPD-Nav classifier");
  expectOneLine((tmp.path() / "none.yml").string(), "no such file");
  expectOneLine((tmp.path() / "m.model").string(), "extension");
  EXPECT_THROW(c->save((tmp.path() / "m.bin").string()), std::invalid_argument);
  std::vector<Label> one_class(t.size(), Label::Traversable);
  EXPECT_THROW(PointClassifier::train(f, one_class, fp, p), std::invalid_argument);
}

}  // namespace
}  // namespace upd::learn
