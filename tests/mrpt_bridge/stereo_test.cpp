// Dense stereo on the rectified RTAB-Map pair (indoor hall with a large floor): the floor comes
// out as a near-horizontal plane below the camera, directly and through CObservationStereoImages
// (rectified, and distorted then rectified again by the converter).
#include "upd/mrpt_bridge/stereo.h"
#include "test_data.h"
#include "upd/mrpt_bridge/observation_cloud.h"
#include "upd/mrpt_bridge/pose_source.h"

#include <mrpt/img/CImage.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/poses/CPose3D.h>
#include <mrpt/poses/CPose3DQuat.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

namespace core = upd::core;

namespace {

using upd::core::PointCloud;
using upd::mrpt_bridge::StereoCalibration;
using upd::mrpt_bridge::StereoMatchParams;

struct Plane {
  Eigen::Vector3f n = Eigen::Vector3f::Zero();  ///< unit normal
  float d = 0;                                  ///< n . p + d = 0
  std::size_t inliers = 0;
};

// RANSAC (fixed seed) over the finite points of rows [row_begin, height) of an organized cloud.
Plane dominantPlane(const core::PointCloud& c, std::size_t row_begin, float tol_m) {
  std::vector<Eigen::Vector3f> pts;
  for (std::size_t v = row_begin; v < c.height; ++v) {
    for (std::size_t u = 0; u < c.width; ++u) {
      const std::size_t i = v * c.width + u;
      if (c.isFinite(i)) pts.push_back(c.point(i));
    }
  }
  Plane best;
  if (pts.size() < 3) return best;
  std::mt19937 rng(42);
  std::uniform_int_distribution<std::size_t> pick(0, pts.size() - 1);
  for (int it = 0; it < 300; ++it) {
    const Eigen::Vector3f a = pts[pick(rng)], b = pts[pick(rng)], cc = pts[pick(rng)];
    Eigen::Vector3f n = (b - a).cross(cc - a);
    if (n.norm() < 1e-6f) continue;
    n.normalize();
    const float d = -n.dot(a);
    std::size_t in = 0;
    for (const auto& p : pts) in += std::abs(n.dot(p) + d) < tol_m ? 1 : 0;
    if (in > best.inliers) best = {n, d, in};
  }
  return best;
}

struct Pair {
  cv::Mat left, right;
  StereoCalibration calib;
};

bool loadPair(Pair& pair) {
  const std::string l = upd::test::sharedFile("rtabmap/stereo_rect/left/50.jpg");
  const std::string r = upd::test::sharedFile("rtabmap/stereo_rect/right/50.jpg");
  const std::string ly = upd::test::sharedFile("rtabmap/stereo_rect/stereo_left.yaml");
  const std::string ry = upd::test::sharedFile("rtabmap/stereo_rect/stereo_right.yaml");
  if (l.empty() || r.empty() || ly.empty() || ry.empty()) return false;
  pair.left = cv::imread(l, cv::IMREAD_COLOR);
  pair.right = cv::imread(r, cv::IMREAD_UNCHANGED);
  pair.calib = upd::mrpt_bridge::loadStereoCalibrationYaml(ly, ry);
  return !pair.left.empty() && !pair.right.empty();
}

#define REQUIRE_PAIR(pair)                                                                \
  Pair pair;                                                                              \
  if (!loadPair(pair)) {                                                                  \
    GTEST_SKIP() << "rtabmap/stereo_rect not found under " << upd::test::sharedDataDir(); \
  }

TEST(Stereo, LoadsRtabmapYamlCalibration) {
  REQUIRE_PAIR(pair);
  const StereoCalibration& c = pair.calib;
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_NEAR(c.fx_px, 487.6087, 1e-3);
  EXPECT_NEAR(c.fy_px, 487.6087, 1e-3);
  EXPECT_NEAR(c.cx_px, 318.1162, 1e-3);
  EXPECT_NEAR(c.cy_px, 249.4442, 1e-3);
  EXPECT_NEAR(c.baseline_m, 58.3627 / 487.6087, 1e-5);
}

TEST(Stereo, YamlErrorsNameTheFile) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string missing = (dir / "upd_no_such_stereo.yaml").string();
  try {
    upd::mrpt_bridge::loadStereoCalibrationYaml(missing, missing);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
  const std::string ry = upd::test::sharedFile("rtabmap/stereo_rect/stereo_right.yaml");
  if (ry.empty()) return;
  const std::string bad = (dir / "upd_stereo_no_matrix.yaml").string();
  std::ofstream(bad) << "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n";
  try {
    upd::mrpt_bridge::loadStereoCalibrationYaml(bad, ry);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("camera_matrix"), std::string::npos) << e.what();
  }
  std::filesystem::remove(bad);
}

// A word among a matrix's numbers (OpenCV throws while reading it): one line naming the files.
TEST(Stereo, WordInAMatrixIsOneLine) {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string left = (dir / "upd_stereo_word_left.yaml").string();
  const std::string right = (dir / "upd_stereo_word_right.yaml").string();
  const std::string head = "%YAML:1.0\n---\nimage_width: 640\nimage_height: 480\n";
  std::ofstream(left) << head << "camera_matrix:\n   rows: 3\n   cols: 3\n"
                      << "   data: [ 500., 0., 320., 0., focal, 240., 0., 0., 1. ]\n";
  std::ofstream(right) << head << "projection_matrix:\n   rows: 3\n   cols: 4\n"
                       << "   data: [ 500., 0., 320., -60., 0., 500., 240., 0., 0., 0., 1., 0. ]\n";
  try {
    upd::mrpt_bridge::loadStereoCalibrationYaml(left, right);
    ADD_FAILURE() << "read";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("stereo calibration " + left + " / " + right + ": "), std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  std::filesystem::remove(left);
  std::filesystem::remove(right);
}

TEST(Stereo, RtabmapPairGivesHorizontalFloorBelowCamera) {
  REQUIRE_PAIR(pair);
  const StereoMatchParams params;
  const core::PointCloud cloud =
      upd::mrpt_bridge::stereoToCloud(pair.left, pair.right, pair.calib, params, true);
  ASSERT_EQ(cloud.width, 640u);
  ASSERT_EQ(cloud.height, 480u);
  EXPECT_TRUE(cloud.hasColor());
  const std::size_t valid = cloud.countFinite();
  EXPECT_GT(valid, 640u * 480u / 5) << "too few disparities";
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.isFinite(i)) continue;
    ASSERT_GE(cloud.z[i], params.min_depth_m - 1e-4);
    ASSERT_LE(cloud.z[i], params.max_depth_m + 1e-4);
  }
  // The floor fills the lower part of the image.
  const Plane floor = dominantPlane(cloud, cloud.height * 2 / 3, 0.03f);
  ASSERT_GT(floor.inliers, 1000u);
  Eigen::Vector3f n = floor.n;
  float d = floor.d;
  if (n.y() > 0) {  // orient the normal up, i.e. towards -y in the optical frame
    n = -n;
    d = -d;
  }
  const double angle_deg = std::acos(std::clamp(-n.y(), -1.f, 1.f)) * 180.0 / M_PI;
  EXPECT_LT(angle_deg, 20.0) << "floor normal " << n.transpose();
  const double height_m = d;  // distance of the camera above the plane (n points up)
  EXPECT_GT(height_m, 0.2);
  EXPECT_LT(height_m, 2.0);
  RecordProperty("floor_angle_deg", std::to_string(angle_deg));
  RecordProperty("camera_height_m", std::to_string(height_m));
}

mrpt::obs::CObservationStereoImages makeObservation(const Pair& pair, const cv::Mat& left,
                                                    const cv::Mat& right,
                                                    const std::array<double, 8>& dist) {
  mrpt::obs::CObservationStereoImages obs;
  obs.imageLeft = mrpt::img::CImage(left, mrpt::img::DEEP_COPY);
  obs.imageRight = mrpt::img::CImage(right, mrpt::img::DEEP_COPY);
  obs.hasImageRight = true;
  for (auto* cam : {&obs.leftCamera, &obs.rightCamera}) {
    cam->ncols = pair.calib.width;
    cam->nrows = pair.calib.height;
    cam->setIntrinsicParamsFromValues(pair.calib.fx_px, pair.calib.fy_px, pair.calib.cx_px,
                                      pair.calib.cy_px);
    cam->dist = dist;
  }
  obs.rightCameraPose =
      mrpt::poses::CPose3DQuat(mrpt::poses::CPose3D(pair.calib.baseline_m, 0, 0, 0, 0, 0));
  // A forward-looking camera 0.5 m above the robot origin: optical z = robot x, x = -y, y = -z.
  obs.cameraPose =
      mrpt::poses::CPose3DQuat(mrpt::poses::CPose3D(0.1, 0.0, 0.5, -M_PI / 2, 0.0, -M_PI / 2));
  return obs;
}

TEST(Stereo, ObservationPathGivesTheSameCloudInTheRobotFrame) {
  REQUIRE_PAIR(pair);
  cv::Mat right_grey;
  if (pair.right.channels() == 3) {
    cv::cvtColor(pair.right, right_grey, cv::COLOR_BGR2GRAY);
  } else {
    right_grey = pair.right;
  }
  const auto obs = makeObservation(pair, pair.left, right_grey, {});
  ASSERT_TRUE(obs.areImagesRectified());
  const upd::mrpt_bridge::ObservationCloud oc = upd::mrpt_bridge::toCloud(obs);
  ASSERT_TRUE(oc.ok()) << oc.skipped_reason;
  EXPECT_EQ(oc.source_class, "CObservationStereoImages");
  ASSERT_TRUE(oc.organized());
  const core::PointCloud direct =
      upd::mrpt_bridge::stereoToCloud(pair.left, right_grey, pair.calib, StereoMatchParams(), true);
  const core::PointCloud expected = upd::core::transformCloud(
      direct, upd::mrpt_bridge::toIsometry(mrpt::poses::CPose3D(obs.cameraPose)));
  ASSERT_EQ(oc.cloud_in_robot.size(), expected.size());
  EXPECT_EQ(oc.cloud_in_robot.countFinite(), expected.countFinite());
  for (std::size_t i = 0; i < expected.size(); i += 101) {
    if (!expected.isFinite(i)) continue;
    EXPECT_TRUE(oc.cloud_in_robot.point(i).isApprox(expected.point(i), 1e-5f)) << i;
  }
  EXPECT_TRUE(oc.cloud_in_robot.sensor_origin.isApprox(Eigen::Vector3f(0.1f, 0.f, 0.5f), 1e-5f));
  // In the robot frame (z up) the floor is roughly horizontal.
  const Plane floor = dominantPlane(oc.cloud_in_robot, 320, 0.03f);
  EXPECT_GT(std::abs(floor.n.z()), std::cos(20.0 * M_PI / 180.0));

  // A calibration override from SourceParams replaces a missing one.
  auto no_calib = obs;
  no_calib.leftCamera = mrpt::img::TCamera();
  no_calib.leftCamera.setIntrinsicParamsFromValues(0, 0, 0, 0);
  no_calib.rightCameraPose = mrpt::poses::CPose3DQuat();
  const auto skipped = upd::mrpt_bridge::toCloud(no_calib);
  EXPECT_FALSE(skipped.ok());
  EXPECT_NE(skipped.skipped_reason.find("stereo_fx_px"), std::string::npos);
  upd::mrpt_bridge::SourceParams sp;
  sp.stereo_fx_px = pair.calib.fx_px;
  sp.stereo_fy_px = pair.calib.fy_px;
  sp.stereo_cx_px = pair.calib.cx_px;
  sp.stereo_cy_px = pair.calib.cy_px;
  sp.stereo_baseline_m = pair.calib.baseline_m;
  const auto overridden = upd::mrpt_bridge::toCloud(no_calib, sp);
  ASSERT_TRUE(overridden.ok()) << overridden.skipped_reason;
  EXPECT_EQ(overridden.cloud_in_robot.countFinite(), expected.countFinite());

  auto no_right = obs;
  no_right.hasImageRight = false;
  EXPECT_EQ(upd::mrpt_bridge::toCloud(no_right).skipped_reason,
            "CObservationStereoImages without a right image");
}

// Distort the rectified pair with a known lens model; the converter must undo it (rectify with
// OpenCV) and find the same floor.
TEST(Stereo, DistortedObservationIsRectifiedFirst) {
  REQUIRE_PAIR(pair);
  cv::Mat right_grey;
  if (pair.right.channels() == 3) {
    cv::cvtColor(pair.right, right_grey, cv::COLOR_BGR2GRAY);
  } else {
    right_grey = pair.right;
  }
  const std::array<double, 8> dist{-0.08, 0.01, 0, 0, 0, 0, 0, 0};
  cv::Mat k = cv::Mat::eye(3, 3, CV_64F);
  k.at<double>(0, 0) = pair.calib.fx_px;
  k.at<double>(1, 1) = pair.calib.fy_px;
  k.at<double>(0, 2) = pair.calib.cx_px;
  k.at<double>(1, 2) = pair.calib.cy_px;
  const cv::Mat d(1, 8, CV_64F, const_cast<double*>(dist.data()));
  // For every pixel of the distorted image, where it comes from in the undistorted one.
  std::vector<cv::Point2f> distorted_px, undistorted_px;
  for (int v = 0; v < pair.calib.height; ++v) {
    for (int u = 0; u < pair.calib.width; ++u) distorted_px.emplace_back(u, v);
  }
  cv::undistortPoints(distorted_px, undistorted_px, k, d, cv::noArray(), k);
  cv::Mat mx(pair.calib.height, pair.calib.width, CV_32F), my(mx.size(), CV_32F);
  for (std::size_t i = 0; i < undistorted_px.size(); ++i) {
    mx.at<float>(static_cast<int>(i)) = undistorted_px[i].x;
    my.at<float>(static_cast<int>(i)) = undistorted_px[i].y;
  }
  cv::Mat left_d, right_d;
  cv::remap(pair.left, left_d, mx, my, cv::INTER_LINEAR);
  cv::remap(right_grey, right_d, mx, my, cv::INTER_LINEAR);

  const auto rectified_obs = makeObservation(pair, pair.left, right_grey, {});
  const auto distorted_obs = makeObservation(pair, left_d, right_d, dist);
  ASSERT_FALSE(distorted_obs.areImagesRectified());
  const auto ref = upd::mrpt_bridge::toCloud(rectified_obs);
  const auto got = upd::mrpt_bridge::toCloud(distorted_obs);
  ASSERT_TRUE(ref.ok() && got.ok()) << got.skipped_reason;
  const Plane a = dominantPlane(ref.cloud_in_robot, 320, 0.03f);
  const Plane b = dominantPlane(got.cloud_in_robot, 320, 0.03f);
  ASSERT_GT(b.inliers, 1000u);
  const double angle_deg = std::acos(std::min(1.f, std::abs(a.n.dot(b.n)))) * 180.0 / M_PI;
  EXPECT_LT(angle_deg, 5.0);
  EXPECT_NEAR(std::abs(b.d), std::abs(a.d), 0.1 * std::abs(a.d));
}

TEST(Stereo, BadInputsThrow) {
  const StereoMatchParams params;
  cv::Mat a(100, 120, CV_8UC1, cv::Scalar(10)), b(100, 110, CV_8UC1, cv::Scalar(10));
  EXPECT_THROW(upd::mrpt_bridge::computeDisparity(a, b, params), std::invalid_argument);
  cv::Mat f(100, 120, CV_32F);
  EXPECT_THROW(upd::mrpt_bridge::computeDisparity(f, f, params), std::invalid_argument);
  StereoMatchParams bad;
  bad.block_size_px = 4;
  EXPECT_THROW(upd::mrpt_bridge::computeDisparity(a, a, bad), std::invalid_argument);
  StereoCalibration calib;
  EXPECT_THROW(calib.validate(), std::invalid_argument);
}

}  // namespace
