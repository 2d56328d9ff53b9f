// CObservationStereoImages to a cloud in the robot frame: the pair loaded, rectified by its
// own calibration where it is not rectified (or the calibration of [SourceParams]), the
// disparity's points (stereo.h) moved by the sensor's pose on the robot.
#include "observation_stereo.h"

#include "mrpt_util.h"
#include "upd/mrpt_bridge/pose_source.h"
#include "upd/mrpt_bridge/stereo.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <mrpt/img/CImage.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/poses/CPose3D.h>

#include <string>

namespace upd::mrpt_bridge::detail {

namespace {

cv::Mat intrinsicMatrix(const mrpt::img::TCamera& cam) {
  cv::Mat k = cv::Mat::eye(3, 3, CV_64F);
  k.at<double>(0, 0) = cam.fx();
  k.at<double>(1, 1) = cam.fy();
  k.at<double>(0, 2) = cam.cx();
  k.at<double>(1, 2) = cam.cy();
  return k;
}

cv::Mat distortion(const mrpt::img::TCamera& cam) {
  cv::Mat d(1, 8, CV_64F);  // MRPT and OpenCV share the order k1 k2 p1 p2 k3 k4 k5 k6
  for (int i = 0; i < 8; ++i) d.at<double>(0, i) = cam.dist[i];
  return d;
}

// The pair's images, loaded; false (and out.skipped_reason) when they are missing or unusable.
bool loadStereoPair(const mrpt::obs::CObservationStereoImages& o, cv::Mat& left, cv::Mat& right,
                    ObservationCloud& out) {
  if (!o.hasImageRight) {
    out.skipped_reason = "CObservationStereoImages without a right image";
    return false;
  }
  try {
    o.imageLeft.forceLoad();
    o.imageRight.forceLoad();
    left = o.imageLeft.asCvMatRef();
    right = o.imageRight.asCvMatRef();
  } catch (const std::exception& e) {
    out.skipped_reason = "CObservationStereoImages: cannot load its images (" +
                         detail::condenseMessage(e.what()) + ")";
    return false;
  }
  if (!usableImage(left) || !usableImage(right) || left.size() != right.size()) {
    out.skipped_reason =
        "CObservationStereoImages: the images are empty, not 8-bit, or differ in size";
    return false;
  }
  return true;
}

// Rectifies a distorted pair with OpenCV in place, sets the rectified calibration and returns
// the rectified frame's pose in the left camera frame.
Eigen::Isometry3d rectifyPair(const mrpt::img::TCamera& lc, const mrpt::img::TCamera& rc,
                              const mrpt::poses::CPose3D& right_in_left, cv::Mat& left,
                              cv::Mat& right, StereoCalibration& calib) {
  // OpenCV wants the transform from the left to the right camera frame (p_right = R p_left +
  // T); MRPT gives the right camera's pose in the left frame, its inverse.
  const Eigen::Isometry3d left_to_right = toIsometry(right_in_left).inverse();
  cv::Mat r(3, 3, CV_64F), t(3, 1, CV_64F);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r.at<double>(i, j) = left_to_right.linear()(i, j);
    t.at<double>(i, 0) = left_to_right.translation()(i);
  }
  cv::Mat r1, r2, p1, p2, q;
  const cv::Size size(left.cols, left.rows);
  cv::stereoRectify(intrinsicMatrix(lc), distortion(lc), intrinsicMatrix(rc), distortion(rc),
                    size, r, t, r1, r2, p1, p2, q, cv::CALIB_ZERO_DISPARITY, 0);
  cv::Mat mx, my, left_rect, right_rect;
  cv::initUndistortRectifyMap(intrinsicMatrix(lc), distortion(lc), r1, p1, size, CV_32FC1, mx,
                              my);
  cv::remap(left, left_rect, mx, my, cv::INTER_LINEAR);
  cv::initUndistortRectifyMap(intrinsicMatrix(rc), distortion(rc), r2, p2, size, CV_32FC1, mx,
                              my);
  cv::remap(right, right_rect, mx, my, cv::INTER_LINEAR);
  left = left_rect;
  right = right_rect;
  calib.fx_px = p1.at<double>(0, 0);
  calib.fy_px = p1.at<double>(1, 1);
  calib.cx_px = p1.at<double>(0, 2);
  calib.cy_px = p1.at<double>(1, 2);
  calib.baseline_m = -p2.at<double>(0, 3) / p2.at<double>(0, 0);
  // R1 rotates left-camera coordinates into the rectified frame: p_rect = R1 p_left.
  Eigen::Matrix3d r1e;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r1e(i, j) = r1.at<double>(i, j);
  }
  Eigen::Isometry3d rectified_in_left = Eigen::Isometry3d::Identity();
  rectified_in_left.linear() = r1e.transpose();
  return rectified_in_left;
}

// The calibration the observation carries (rectifying the pair when it is distorted); false
// (and out.skipped_reason) when it has none usable.
bool calibrationFromObservation(const mrpt::obs::CObservationStereoImages& o, cv::Mat& left,
                                cv::Mat& right, StereoCalibration& calib,
                                Eigen::Isometry3d& rectified_in_left, ObservationCloud& out) {
  mrpt::img::TCamera lc = o.leftCamera, rc = o.rightCamera;
  if (lc.ncols != static_cast<uint32_t>(left.cols) ||
      lc.nrows != static_cast<uint32_t>(left.rows)) {
    lc.scaleToResolution(left.cols, left.rows);
  }
  if (rc.ncols != static_cast<uint32_t>(left.cols) ||
      rc.nrows != static_cast<uint32_t>(left.rows)) {
    rc.scaleToResolution(left.cols, left.rows);
  }
  const mrpt::poses::CPose3D right_in_left(o.rightCameraPose);
  if (!(lc.fx() > 0) || !(lc.fy() > 0) || !(right_in_left.x() > 0)) {
    out.skipped_reason =
        "CObservationStereoImages without a usable calibration (fx = " + std::to_string(lc.fx()) +
        " px, right camera x = " + std::to_string(right_in_left.x()) +
        " m); set stereo_fx_px, stereo_fy_px, stereo_cx_px, stereo_cy_px, stereo_baseline_m in "
        "[SourceParams]";
    return false;
  }
  if (o.areImagesRectified()) {
    calib.fx_px = lc.fx();
    calib.fy_px = lc.fy();
    calib.cx_px = lc.cx();
    calib.cy_px = lc.cy();
    calib.baseline_m = right_in_left.x();
  } else {
    rectified_in_left = rectifyPair(lc, rc, right_in_left, left, right, calib);
  }
  return true;
}

}  // namespace

void convertStereo(const mrpt::obs::CObservationStereoImages& o, const SourceParams& params,
                   ObservationCloud& out) {
  cv::Mat left, right;
  if (!loadStereoPair(o, left, right, out)) return;
  StereoCalibration calib;
  calib.width = left.cols;
  calib.height = left.rows;
  Eigen::Isometry3d rectified_in_left = Eigen::Isometry3d::Identity();
  if (params.hasStereoCalibration()) {
    calib.fx_px = params.stereo_fx_px;
    calib.fy_px = params.stereo_fy_px;
    calib.cx_px = params.stereo_cx_px;
    calib.cy_px = params.stereo_cy_px;
    calib.baseline_m = params.stereo_baseline_m;
  } else if (!calibrationFromObservation(o, left, right, calib, rectified_in_left, out)) {
    return;
  }
  out.sensor_pose_on_robot = out.sensor_pose_on_robot * rectified_in_left;
  const core::PointCloud in_camera =
      stereoToCloud(left, right, calib, params.stereo, params.color_enabled);
  core::transformCloud(in_camera, out.sensor_pose_on_robot, out.cloud_in_robot);
}

}  // namespace upd::mrpt_bridge::detail
