// Dense stereo: a rectified image pair to an organized point cloud, with OpenCV's StereoSGBM.
//
// MRPT has no dense stereo matcher, so the disparity comes from cv::StereoSGBM (semi-global
// block matching, Hirschmuller 2008). For a rectified pair, a pixel (u, v) of the left image
// with disparity d [px] is at depth z = fx * baseline / d in the LEFT camera-optical frame
// (x right, y down, z forward); x and y follow from the pinhole model (upd::depthToCloud). The
// cloud keeps the image layout: pixel (u, v) is point v * width + u, NaN where the matcher
// found no disparity or the depth falls outside [min_depth_m, max_depth_m].
//
// The calibration is that of the rectified left camera plus the baseline; it comes from the
// MRPT observation (CObservationStereoImages) or from files, e.g. RTAB-Map's OpenCV-YAML pair
// (`<name>_left.yaml`, `<name>_right.yaml`: camera_matrix and projection_matrix, where the right
// projection holds Tx = -fx * baseline).
#pragma once

#include "upd/core/camera.h"
#include "upd/core/point_cloud.h"

#include <string>

namespace cv {
class Mat;
}

namespace upd::mrpt_bridge {

/// A rectified stereo pair's geometry.
struct StereoCalibration {
  int width = 0;          ///< [px]
  int height = 0;         ///< [px]
  double fx_px = 0;       ///< focal length of the rectified left camera [px]
  double fy_px = 0;       ///< [px]
  double cx_px = 0;       ///< principal point [px]
  double cy_px = 0;       ///< [px]
  double baseline_m = 0;  ///< distance between the optical centres [m]

  /// Throws std::invalid_argument naming the field and value.
  void validate() const;
  core::CameraIntrinsics leftIntrinsics() const;
};

/// Semi-global matching and the depth range kept.
struct StereoMatchParams {
  int min_disparity_px = 0;
  int num_disparities_px = 128;  ///< search range; a positive multiple of 16
  int block_size_px = 5;         ///< matched block side; odd, >= 1
  int uniqueness_ratio = 10;     ///< [%] margin by which the best match must win
  int speckle_window_px = 100;   ///< speckle filter region size (0 = off) [px]
  int speckle_range_px = 2;      ///< max disparity variation inside a speckle region [px]
  int disp12_max_diff_px = 1;    ///< left-right consistency tolerance (< 0 = off) [px]
  bool full_dp = false;          ///< full-scale two-pass dynamic programming (more memory)
  double min_depth_m = 0.2;      ///< nearer points become NaN [m]
  double max_depth_m = 20.0;     ///< farther points become NaN [m]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("min_disparity_px", min_disparity_px, "smallest disparity searched [px]");
    v("num_disparities_px", num_disparities_px, "disparity search range, a multiple of 16 [px]");
    v("block_size_px", block_size_px, "matched block side, odd [px]");
    v("uniqueness_ratio", uniqueness_ratio, "margin (%) by which the best match must win");
    v("speckle_window_px", speckle_window_px, "speckle filter region size, 0 = off [px]");
    v("speckle_range_px", speckle_range_px, "max disparity variation in a speckle region [px]");
    v("disp12_max_diff_px", disp12_max_diff_px, "left-right check tolerance, < 0 = off [px]");
    v("full_dp", full_dp, "full two-pass dynamic programming (more memory)");
    v("min_depth_m", min_depth_m, "nearer points are dropped (NaN) [m]");
    v("max_depth_m", max_depth_m, "farther points are dropped (NaN) [m]");
  }
};

/// Disparity of the left image [px] as CV_32F, same size; NaN where none was found. Both
/// images must be rectified and of equal size, 8-bit grey or BGR (BGR is converted to grey).
/// Throws std::invalid_argument on bad images or parameters.
cv::Mat computeDisparity(const cv::Mat& left_rect, const cv::Mat& right_rect,
                         const StereoMatchParams& params);

/// Disparity [px] (CV_32F) to metric depth (z) with the calibration; 0 where invalid.
core::DepthImage disparityToDepth(const cv::Mat& disparity_px, const StereoCalibration& calib,
                            const StereoMatchParams& params);

/// The whole chain: organized cloud in the LEFT camera-optical frame, coloured from the left
/// image when with_color (BGR or grey). sensor_origin = 0 (the left optical centre).
core::PointCloud stereoToCloud(const cv::Mat& left_rect, const cv::Mat& right_rect,
                         const StereoCalibration& calib, const StereoMatchParams& params,
                         bool with_color = true);

/// Reads RTAB-Map/ROS-style OpenCV YAML calibration files of a rectified pair: image_width,
/// image_height and camera_matrix (or projection_matrix) of the left file give the intrinsics;
/// the right projection_matrix gives baseline = -P(0,3) / P(0,0). Throws std::runtime_error
/// naming the file and key that is missing or wrong.
StereoCalibration loadStereoCalibrationYaml(const std::string& left_yaml,
                                            const std::string& right_yaml);

}  // namespace upd::mrpt_bridge
