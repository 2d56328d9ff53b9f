// The JSON summary: required keys, counts that add up, a histogram over [0.70, 1] with
// clamped ends, parameters in ini units, and never a NaN in the text.
#include "io_test_util.h"
#include "upd/io/json_io.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numeric>
#include <random>
#include <sstream>
#include <string>

namespace core = upd::core;

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using upd::core::Label;

const float kNan = std::numeric_limits<float>::quiet_NaN();

using upd::test::TempDir;

void expectNoNonFinite(const std::string& text) {
  for (const char* bad : {"nan", "NaN", "inf", "Infinity"}) {
    EXPECT_EQ(text.find(bad), std::string::npos) << bad << " in\n" << text;
  }
}

std::size_t sumCounts(const json& h) {
  std::size_t s = 0;
  for (const auto& c : h.at("counts")) s += c.get<std::size_t>();
  return s;
}

/// A hand-made result: 6 points in the scored cloud, one of them non-finite, two without zeta.
upd::core::PipelineResult handMadeResult() {
  upd::core::PipelineResult r;
  r.cloud.push_back(0, 0, 0);
  r.cloud.push_back(1, 0, 0);
  r.cloud.push_back(2, 0, 0);
  r.cloud.push_back(3, 0, 0);
  r.cloud.push_back(kNan, kNan, kNan);
  r.cloud.push_back(5, 0, 0);
  r.upd.zeta = {1.f, 0.5f, 0.9f, 0.9999f, kNan, kNan};
  r.upd.rx = r.upd.ry = std::vector<float>(6, 0.f);
  r.upd.rz = {1, 1, 1, 1, kNan, kNan};
  r.upd.invalid = 2;
  r.classes.label = {core::Label::Traversable, core::Label::NonTraversable, core::Label::NonTraversable,
                     core::Label::Traversable, core::Label::Unknown, core::Label::Unknown};
  r.classes.cost = {0.f, 1.f, 1.f, 0.f, kNan, kNan};
  r.preprocess_stats.points_in = 10;
  r.preprocess_stats.non_finite = 4;  // 3 dropped, 1 kept in the scored cloud
  r.preprocess_stats.points_out = 6;
  r.timings.preprocess_ms = 1.5;
  r.timings.normals_ms = 2;
  r.timings.upd_ms = 3;
  r.timings.classify_ms = 0.25;
  r.timings.total_ms = 7;
  return r;
}

TEST(JsonIo, SummaryHasTheRequiredKeysAndConsistentCounts) {
  const upd::core::PipelineResult r = handMadeResult();
  upd::core::PipelineParams p;
  p.upd.radius_m = 0.75;
  const json j = upd::io::summaryJson(r, p, 10);

  for (const char* key : {"points_in", "points_scored", "points_invalid", "radius_m", "zeta",
                          "labels", "timing_ms", "preprocess", "params"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["points_in"], 10);
  EXPECT_EQ(j["points_scored"], 4);
  EXPECT_EQ(j["points_invalid"], 2 + 3);  // two without zeta + three dropped non-finite
  EXPECT_EQ(j["points_after_preprocess"], 6);
  EXPECT_DOUBLE_EQ(j["radius_m"].get<double>(), 0.75);

  const json& z = j["zeta"];
  EXPECT_FLOAT_EQ(z["min"].get<float>(), 0.5f);
  EXPECT_FLOAT_EQ(z["max"].get<float>(), 1.f);
  EXPECT_NEAR(z["mean"].get<double>(), (1.0 + 0.5 + 0.9 + 0.9999) / 4, 1e-6);
  const json& h = z["histogram"];
  ASSERT_EQ(h["edges"].size(), static_cast<std::size_t>(upd::io::kZetaHistogramBins + 1));
  ASSERT_EQ(h["counts"].size(), static_cast<std::size_t>(upd::io::kZetaHistogramBins));
  EXPECT_DOUBLE_EQ(h["edges"].front().get<double>(), upd::io::kZetaHistogramMin);
  EXPECT_DOUBLE_EQ(h["edges"].back().get<double>(), 1.0);
  EXPECT_LT(upd::io::kZetaHistogramMin, std::sqrt(2.0) / 2);
  EXPECT_EQ(sumCounts(h), 4u);
  EXPECT_EQ(h["counts"].front(), 1);  // 0.5 clamps into the first bin
  EXPECT_EQ(h["counts"].back(), 2);   // 1.0 and 0.9999

  EXPECT_EQ(j["labels"]["traversable"], 2);
  EXPECT_EQ(j["labels"]["non_traversable"], 2);
  EXPECT_EQ(j["labels"]["unknown"], 2);
  for (const char* key : {"preprocess", "normals", "upd", "classify", "total"}) {
    EXPECT_TRUE(j["timing_ms"].contains(key)) << key;
  }
  EXPECT_DOUBLE_EQ(j["timing_ms"]["total"].get<double>(), 7.0);
  EXPECT_EQ(j["preprocess"]["non_finite"], 4);
  EXPECT_EQ(j["preprocess"]["points_out"], 6);

  expectNoNonFinite(j.dump());
}

/// Counts the fields a params struct's visit() lists.
struct FieldCounter {
  int n = 0;
  template <class T>
  void operator()(const char*, T&, const char*) {
    ++n;
  }
  void angleDeg(const char*, double&, const char*) { ++n; }
  template <class E, std::size_t N>
  void choice(const char*, E&, const upd::core::EnumName<E> (&)[N], const char*) {
    ++n;
  }
};

TEST(JsonIo, ParamsUseIniKeysAndDegrees) {
  upd::core::PipelineParams p;
  p.up = Eigen::Vector3f(0, -1, 0);
  p.classify.max_slope_rad = 30.0 * upd::core::kDegToRad;
  p.preprocess.voxel_m = 0.05;
  const json j = upd::io::paramsJson(p);
  EXPECT_EQ(j["up"], json::array({0.0, -1.0, 0.0}));
  EXPECT_NEAR(j["classify"]["max_slope_deg"].get<double>(), 30.0, 1e-9);
  EXPECT_FALSE(j["classify"].contains("max_slope_rad"));
  EXPECT_NEAR(j["normals"]["vertical_band_deg"].get<double>(),
              upd::core::NormalParams{}.vertical_band_rad * upd::core::kRadToDeg, 1e-9);
  EXPECT_DOUBLE_EQ(j["preprocess"]["voxel_m"].get<double>(), 0.05);
  EXPECT_EQ(j["preprocess"]["voxel_enabled"], true);
  EXPECT_EQ(j["upd"]["min_neighbors"], p.upd.min_neighbors);
  // Enums by their ini name, so the params can be written back into an ini file.
  EXPECT_EQ(j["upd"]["method"], "auto");
  EXPECT_EQ(j["normals"]["weighting"], "uniform");
  // Vector fields print as their float value, not its double expansion.
  EXPECT_EQ(j["preprocess"]["box_min_m"], json::array({-10.0, -10.0, -10.0}));
  // Every field of every struct is there: count them against the structs' own visit().
  upd::core::PipelineParams q = p;
  FieldCounter pre, nor, up, cla;
  q.preprocess.visit(pre);
  q.normals.visit(nor);
  q.upd.visit(up);
  q.classify.visit(cla);
  EXPECT_EQ(j["preprocess"].size(), static_cast<std::size_t>(pre.n));
  EXPECT_EQ(j["normals"].size(), static_cast<std::size_t>(nor.n));
  EXPECT_EQ(j["upd"].size(), static_cast<std::size_t>(up.n));
  EXPECT_EQ(j["classify"].size(), static_cast<std::size_t>(cla.n));
}

TEST(JsonIo, EmptyResultHasNullStatisticsAndNoNan) {
  const upd::core::PipelineResult r;
  const upd::core::PipelineParams p;
  const json j = upd::io::summaryJson(r, p, 0);
  EXPECT_EQ(j["points_scored"], 0);
  EXPECT_EQ(j["points_invalid"], 0);
  EXPECT_TRUE(j["zeta"]["min"].is_null());
  EXPECT_TRUE(j["zeta"]["mean"].is_null());
  EXPECT_TRUE(j["zeta"]["max"].is_null());
  EXPECT_EQ(sumCounts(j["zeta"]["histogram"]), 0u);
  expectNoNonFinite(j.dump());
}

TEST(JsonIo, NonFiniteNumbersBecomeNull) {
  upd::core::PipelineResult r = handMadeResult();
  r.timings.total_ms = std::numeric_limits<double>::infinity();
  upd::core::PipelineParams p;
  p.upd.radius_m = std::numeric_limits<double>::quiet_NaN();  // invalid, but must not leak
  const json j = upd::io::summaryJson(r, p, 10);
  EXPECT_TRUE(j["timing_ms"]["total"].is_null());
  EXPECT_TRUE(j["radius_m"].is_null());
  expectNoNonFinite(j.dump());
}

TEST(JsonIo, HistogramEdgesAndClamping) {
  const std::vector<float> values = {-5.f, 0.f, 0.25f, 0.5f, 0.99f, 1.f, 7.f, kNan};
  const json h = upd::io::histogramJson(values, 0.0, 1.0, 4);
  EXPECT_EQ(h["edges"], json::array({0.0, 0.25, 0.5, 0.75, 1.0}));
  EXPECT_EQ(h["counts"], json::array({2, 1, 1, 3}));
  EXPECT_THROW(upd::io::histogramJson({}, 1.0, 1.0, 4), std::invalid_argument);
  EXPECT_THROW(upd::io::histogramJson({}, 0.0, 1.0, 0), std::invalid_argument);
}

TEST(JsonIo, SummaryOfARealPipelineRun) {
  // A 1 m x 1 m floor with a 0.2 m step (and its riser) in the middle, plus one NaN point
  // kept (no pre-processing) so it is scored as invalid and counted.
  upd::core::PointCloud cloud;
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.f, 0.001f);
  for (int i = 0; i < 40; ++i) {
    for (int k = 0; k < 40; ++k) {
      const float x = 0.025f * static_cast<float>(i);
      const float y = 0.025f * static_cast<float>(k);
      cloud.push_back(x, y, (x < 0.5f ? 0.f : 0.2f) + noise(rng));
    }
  }
  for (int i = 1; i < 8; ++i) {  // the riser of the step
    for (int k = 0; k < 40; ++k) {
      cloud.push_back(0.4875f + noise(rng), 0.025f * static_cast<float>(k),
                      0.025f * static_cast<float>(i));
    }
  }
  cloud.push_back(kNan, kNan, kNan);
  upd::core::PipelineParams p;
  p.preprocess.disableAll();
  p.upd.radius_m = 0.2;
  const upd::core::PipelineResult r = upd::core::runPipeline(cloud, p);
  const json j = upd::io::summaryJson(r, p, cloud.size());
  EXPECT_EQ(j["points_in"], cloud.size());
  const std::size_t scored = j["points_scored"];
  const std::size_t invalid = j["points_invalid"];
  EXPECT_EQ(scored + invalid, cloud.size());
  EXPECT_GE(invalid, 1u);
  EXPECT_EQ(sumCounts(j["zeta"]["histogram"]), scored);
  const auto& l = j["labels"];
  EXPECT_EQ(l["traversable"].get<std::size_t>() + l["non_traversable"].get<std::size_t>() +
                l["unknown"].get<std::size_t>(),
            r.cloud.size());
  EXPECT_GT(l["non_traversable"].get<std::size_t>(), 0u);  // the step's edges
  EXPECT_GT(l["traversable"].get<std::size_t>(), 0u);      // the floors
  // An unorganized cloud with the defaults (method auto, radius neighbourhoods): the fast path.
  EXPECT_EQ(j["method"], "fast");
  EXPECT_EQ(j["normals_method"], "hash grid");
  EXPECT_EQ(j["exact_band"]["points"], 0u);  // off by default
  EXPECT_EQ(j["lattice_cells_per_radius"], r.fast_cells_per_radius);
  EXPECT_GE(r.fast_cells_per_radius, p.upd.fast_cells_per_radius);
  // With the band, the points near zeta_min that got the exact sums are counted.
  upd::core::PipelineParams banded = p;
  banded.upd.fast_exact_band = 0.05;
  const upd::core::PipelineResult rb = upd::core::runPipeline(cloud, banded);
  const json jb = upd::io::summaryJson(rb, banded, cloud.size());
  std::size_t near = 0;
  for (const float z : r.upd.zeta) near += std::abs(z - banded.classify.zeta_min) < 0.05 ? 1 : 0;
  EXPECT_GT(near, 0u);
  EXPECT_EQ(jb["exact_band"]["points"], near);
  EXPECT_EQ(jb["exact_band"]["band"], 0.05);
  p.upd.method = upd::core::UpdMethod::Exact;
  const json exact = upd::io::summaryJson(upd::core::runPipeline(cloud, p), p, cloud.size());
  EXPECT_EQ(exact["method"], "exact");
  EXPECT_EQ(exact["normals_method"], "exact (k-d tree)");
  EXPECT_FALSE(exact.contains("exact_band"));
  EXPECT_FALSE(exact.contains("lattice_cells_per_radius"));

  TempDir dir;
  const std::string f = dir.file("summary.json");
  upd::io::writeJsonAtomically(f, j);
  std::ifstream in(f);
  std::stringstream text;
  text << in.rdbuf();
  expectNoNonFinite(text.str());
  EXPECT_EQ(json::parse(text.str()), j);
  EXPECT_EQ(text.str().back(), '\n');
}

TEST(JsonIo, WriteIntoMissingDirectoryFails) {
  TempDir dir;
  const std::string f = dir.file("nope/summary.json");
  EXPECT_THROW(upd::io::writeJsonAtomically(f, json{{"a", 1}}), std::runtime_error);
}

}  // namespace
