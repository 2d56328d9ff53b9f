// Parameters load from MRPT ini files strictly: values land in the structs (degrees converted),
// and a missing file, an unknown section or key, or a bad value stops with a message naming the
// file, section, key and value.
#include "upd/core/pipeline.h"
#include "upd/mrpt_bridge/ini_params.h"

#include <gtest/gtest.h>

#include "temp_dir.h"
#include "error_of.h"

#include <cmath>
#include <filesystem>
#include <fstream>

namespace core = upd::core;

namespace upd::mrpt_bridge {
namespace {

class IniFile : public ::testing::Test {
 protected:
  std::string write(const std::string& text) {
    path_ = dir_.file(std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) +
                      ".ini");
    std::ofstream(path_) << text;
    return path_;
  }
  std::string errorOf(const std::string& text) {
    const std::string p = write(text);
    core::PipelineParams params;
    return test::errorOf([&] { loadPipelineParams(p, params); });
  }
  test::TempDir dir_;  // removed with its files after each test
  std::string path_;
};

TEST_F(IniFile, ValuesLandInTheStructsAndDegreesBecomeRadians) {
  const std::string p = write(
      "[PipelineParams]\nup = 0,-1,0\n"
      "[UpdParams]\nradius_m = 1.0   // tractor\n"
      "[ClassifyParams]\nmax_slope_deg = 30\nzeta_min = 0.9\n"
      "[PreprocessParams]\nvoxel_enabled = false\nrange_max_m = 8\n");
  core::PipelineParams params;
  loadPipelineParams(p, params);
  EXPECT_EQ(params.up, Eigen::Vector3f(0, -1, 0));
  EXPECT_DOUBLE_EQ(params.upd.radius_m, 1.0);
  EXPECT_NEAR(params.classify.max_slope_rad, 30.0 * M_PI / 180.0, 1e-12);
  EXPECT_DOUBLE_EQ(params.classify.zeta_min, 0.9);
  EXPECT_FALSE(params.preprocess.voxel_enabled);
  EXPECT_DOUBLE_EQ(params.preprocess.range_max_m, 8.0);
  // Keys absent from the file keep their defaults.
  EXPECT_DOUBLE_EQ(params.normals.radius_m, core::NormalParams{}.radius_m);
}

TEST_F(IniFile, MissingFileNamesIt) {
  core::PipelineParams params;
  try {
    loadPipelineParams("/nonexistent/dune.ini", params);
    FAIL() << "no error";
  } catch (const std::exception& e) {
    EXPECT_EQ(std::string(e.what()), "config file /nonexistent/dune.ini: not found");
  }
}

TEST_F(IniFile, UnknownSectionIsNamed) {
  const std::string e = errorOf("[UpdParam]\nradius_m = 0.5\n");
  EXPECT_NE(e.find(path_), std::string::npos) << e;
  EXPECT_NE(e.find("unknown section [UpdParam]"), std::string::npos) << e;
}

TEST_F(IniFile, UnknownKeyIsNamed) {
  const std::string e = errorOf("[UpdParams]\nradius = 0.5\n");
  EXPECT_NE(e.find(path_), std::string::npos) << e;
  EXPECT_NE(e.find("[UpdParams] unknown key 'radius'"), std::string::npos) << e;
}

TEST_F(IniFile, UnparsableValueNamesKeyAndValue) {
  const std::string e = errorOf("[UpdParams]\nradius_m = half a metre\n");
  EXPECT_NE(e.find("[UpdParams] radius_m = 'half a metre': not a number"), std::string::npos)
      << e;
  EXPECT_NE(errorOf("[PreprocessParams]\nvoxel_enabled = maybe\n").find("not a boolean"),
            std::string::npos);
  EXPECT_NE(errorOf("[PipelineParams]\nup = 0,0\n").find("not three numbers"), std::string::npos);
}

TEST_F(IniFile, OutOfRangeValueNamesFileSectionFieldAndValue) {
  const std::string e = errorOf("[UpdParams]\nradius_m = -0.5\n");
  EXPECT_NE(e.find(path_), std::string::npos) << e;
  EXPECT_NE(e.find("UpdParams.radius_m = -0.5: must be > 0"), std::string::npos) << e;
  EXPECT_NE(errorOf("[PipelineParams]\nup = 0,0,0\n").find("PipelineParams.up = 0,0,0"),
            std::string::npos);
}

// Enum keys take their names (any case) and, so that configs written before the names still
// load, the old numbers.
TEST_F(IniFile, EnumsLoadByNameOrOldNumber) {
  core::PipelineParams params;
  loadPipelineParams(write("[UpdParams]\nmethod = exact\n[NormalParams]\nweighting = gaussian\n"),
                     params);
  EXPECT_EQ(params.upd.method, core::UpdMethod::Exact);
  EXPECT_EQ(params.normals.weighting, core::NormalWeighting::Gaussian);
  params = {};
  loadPipelineParams(write("[UpdParams]\nmethod = 2\n[NormalParams]\nweighting = 1\n"), params);
  EXPECT_EQ(params.upd.method, core::UpdMethod::Fast);
  EXPECT_EQ(params.normals.weighting, core::NormalWeighting::Gaussian);
  params = {};
  loadPipelineParams(write("[UpdParams]\nmethod = Auto   ; the default\n"), params);
  EXPECT_EQ(params.upd.method, core::UpdMethod::Auto);
  params = {};
  loadPipelineParams(write("[UpdParams]\nmethod = 1\n[NormalParams]\nweighting = 0\n"), params);
  EXPECT_EQ(params.upd.method, core::UpdMethod::Exact);
  EXPECT_EQ(params.normals.weighting, core::NormalWeighting::Uniform);
}

TEST_F(IniFile, UnknownEnumNameNamesFileKeyValueAndTheValidNames) {
  const std::string p = write("[UpdParams]\nmethod = fastest\n");
  core::PipelineParams params;
  EXPECT_THROW(loadPipelineParams(p, params), std::invalid_argument);
  const std::string e = errorOf("[UpdParams]\nmethod = fastest\n");
  EXPECT_EQ(e, "config file " + path_ +
                   ": [UpdParams] method = 'fastest': not one of auto, exact, fast (or their old "
                   "numbers 0, 1, 2)");
  // A number that names no value is no better than an unknown name.
  EXPECT_NE(errorOf("[UpdParams]\nmethod = 3\n").find("method = '3': not one of auto, exact, fast"),
            std::string::npos);
  EXPECT_NE(errorOf("[NormalParams]\nweighting = 1.0\n")
                .find("[NormalParams] weighting = '1.0': not one of uniform, gaussian"),
            std::string::npos);
}

TEST_F(IniFile, TheFileIsNeverRewritten) {
  const std::string text = "[UpdParams]\nradius_m = 0.7\n";
  const std::string p = write(text);
  {
    core::PipelineParams params;
    loadPipelineParams(p, params);
  }
  std::ifstream in(p);
  const std::string after((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(after, text);
}

}  // namespace
}  // namespace upd::mrpt_bridge
