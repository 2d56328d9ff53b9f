#include "upd/mrpt_bridge/stereo.h"

#include "upd/core/params.h"
#include "yaml_text.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace upd::mrpt_bridge {

void StereoCalibration::validate() const {
  core::requireParam(width > 0, "StereoCalibration", "width", width, "must be > 0");
  core::requireParam(height > 0, "StereoCalibration", "height", height, "must be > 0");
  core::requireParam(std::isfinite(fx_px) && fx_px > 0, "StereoCalibration", "fx_px", fx_px,
               "must be > 0");
  core::requireParam(std::isfinite(fy_px) && fy_px > 0, "StereoCalibration", "fy_px", fy_px,
               "must be > 0");
  core::requireParam(std::isfinite(cx_px), "StereoCalibration", "cx_px", cx_px, "must be finite");
  core::requireParam(std::isfinite(cy_px), "StereoCalibration", "cy_px", cy_px, "must be finite");
  core::requireParam(std::isfinite(baseline_m) && baseline_m > 0, "StereoCalibration", "baseline_m",
               baseline_m, "must be > 0");
}

core::CameraIntrinsics StereoCalibration::leftIntrinsics() const {
  core::CameraIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = fx_px;
  k.fy = fy_px;
  k.cx = cx_px;
  k.cy = cy_px;
  return k;
}

void StereoMatchParams::validate() const {
  const char* o = "StereoMatchParams";
  core::requireParam(num_disparities_px > 0 && num_disparities_px % 16 == 0, o, "num_disparities_px",
               num_disparities_px, "must be a positive multiple of 16");
  core::requireParam(block_size_px >= 1 && block_size_px % 2 == 1 && block_size_px <= 51, o,
               "block_size_px", block_size_px, "must be odd, in [1, 51]");
  core::requireParam(uniqueness_ratio >= 0 && uniqueness_ratio <= 100, o, "uniqueness_ratio",
               uniqueness_ratio, "must be in [0, 100]");
  core::requireParam(speckle_window_px >= 0, o, "speckle_window_px", speckle_window_px, "must be >= 0");
  core::requireParam(speckle_range_px >= 0, o, "speckle_range_px", speckle_range_px, "must be >= 0");
  core::requireParam(std::isfinite(min_depth_m) && min_depth_m >= 0, o, "min_depth_m", min_depth_m,
               "must be >= 0");
  core::requireParam(std::isfinite(max_depth_m) && max_depth_m > min_depth_m, o, "max_depth_m",
               max_depth_m, "must be > min_depth_m");
}

namespace {

cv::Mat toGrey(const cv::Mat& img, const char* which) {
  if (img.empty())
    throw std::invalid_argument(std::string("stereo: the ") + which + " image is empty");
  if (img.type() == CV_8UC1) return img;
  cv::Mat grey;
  if (img.type() == CV_8UC3) {
    cv::cvtColor(img, grey, cv::COLOR_BGR2GRAY);
  } else if (img.type() == CV_8UC4) {
    cv::cvtColor(img, grey, cv::COLOR_BGRA2GRAY);
  } else {
    throw std::invalid_argument(std::string("stereo: the ") + which +
                                " image must be 8-bit grey, BGR or BGRA");
  }
  return grey;
}

}  // namespace

cv::Mat computeDisparity(const cv::Mat& left_rect, const cv::Mat& right_rect,
                         const StereoMatchParams& params) {
  params.validate();
  const cv::Mat left = toGrey(left_rect, "left");
  const cv::Mat right = toGrey(right_rect, "right");
  if (left.size() != right.size()) {
    throw std::invalid_argument("stereo: left image is " + std::to_string(left.cols) + "x" +
                                std::to_string(left.rows) + " but the right one is " +
                                std::to_string(right.cols) + "x" + std::to_string(right.rows));
  }
  const int bs = params.block_size_px;
  // P1, P2: the smoothness penalties recommended by OpenCV for one channel.
  auto sgbm =
      cv::StereoSGBM::create(params.min_disparity_px, params.num_disparities_px, bs, 8 * bs * bs,
                             32 * bs * bs, params.disp12_max_diff_px, 63, params.uniqueness_ratio,
                             params.speckle_window_px, params.speckle_range_px,
                             params.full_dp ? cv::StereoSGBM::MODE_HH : cv::StereoSGBM::MODE_SGBM);
  cv::Mat disp16;
  sgbm->compute(left, right, disp16);  // CV_16S, 4 fractional bits

  cv::Mat disp(disp16.size(), CV_32F);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const int invalid_below = params.min_disparity_px * 16;  // OpenCV marks (min - 1) * 16
  for (int v = 0; v < disp16.rows; ++v) {
    const auto* in = disp16.ptr<int16_t>(v);
    auto* out = disp.ptr<float>(v);
    for (int u = 0; u < disp16.cols; ++u) {
      out[u] = in[u] < invalid_below ? nan : static_cast<float>(in[u]) / 16.f;
    }
  }
  return disp;
}

core::DepthImage disparityToDepth(const cv::Mat& disparity_px, const StereoCalibration& calib,
                            const StereoMatchParams& params) {
  calib.validate();
  params.validate();
  if (disparity_px.type() != CV_32F || disparity_px.cols != calib.width ||
      disparity_px.rows != calib.height) {
    throw std::invalid_argument("stereo: the disparity must be CV_32F " +
                                std::to_string(calib.width) + "x" + std::to_string(calib.height) +
                                " (the calibration's size)");
  }
  core::DepthImage depth;
  depth.width = calib.width;
  depth.height = calib.height;
  depth.depth_m.assign(static_cast<std::size_t>(calib.width) * calib.height, 0.f);
  const double fb = calib.fx_px * calib.baseline_m;
  for (int v = 0; v < calib.height; ++v) {
    const auto* d = disparity_px.ptr<float>(v);
    for (int u = 0; u < calib.width; ++u) {
      if (!(d[u] > 0.f)) continue;  // also NaN
      const double z = fb / d[u];
      if (z < params.min_depth_m || z > params.max_depth_m) continue;
      depth.depth_m[static_cast<std::size_t>(v) * calib.width + u] = static_cast<float>(z);
    }
  }
  return depth;
}

core::PointCloud stereoToCloud(const cv::Mat& left_rect, const cv::Mat& right_rect,
                         const StereoCalibration& calib, const StereoMatchParams& params,
                         bool with_color) {
  calib.validate();
  if (left_rect.cols != calib.width || left_rect.rows != calib.height) {
    throw std::invalid_argument("stereo: the images are " + std::to_string(left_rect.cols) + "x" +
                                std::to_string(left_rect.rows) + " but the calibration is for " +
                                std::to_string(calib.width) + "x" + std::to_string(calib.height));
  }
  const cv::Mat disparity = computeDisparity(left_rect, right_rect, params);
  core::PointCloud cloud =
      core::depthToCloud(disparityToDepth(disparity, calib, params), calib.leftIntrinsics());
  if (with_color &&
      (left_rect.type() == CV_8UC3 || left_rect.type() == CV_8UC1 || left_rect.type() == CV_8UC4)) {
    cloud.resize(cloud.size(), true);
    const int channels = left_rect.channels();
    for (int v = 0; v < left_rect.rows; ++v) {
      const auto* row = left_rect.ptr<uint8_t>(v);
      for (int u = 0; u < left_rect.cols; ++u) {
        const std::size_t i = static_cast<std::size_t>(v) * left_rect.cols + u;
        const uint8_t* px = row + static_cast<std::size_t>(u) * channels;
        if (channels == 1) {
          cloud.r[i] = cloud.g[i] = cloud.b[i] = px[0];
        } else {  // OpenCV order: BGR(A)
          cloud.b[i] = px[0];
          cloud.g[i] = px[1];
          cloud.r[i] = px[2];
        }
      }
    }
  }
  return cloud;
}

namespace {

// A 3x3 or 3x4 matrix stored either as an OpenCV matrix or ROS-style {rows, cols, data: [...]}.
cv::Mat readMatrix(const cv::FileStorage& fs, const std::string& file, const std::string& key,
                   int rows, int cols) {
  const cv::FileNode node = fs[key];
  if (node.empty())
    throw std::runtime_error("stereo calibration " + file + ": no key '" + key + "'");
  cv::Mat m;
  if (node.isMap() && !node["data"].empty() && node["data"].isSeq()) {
    std::vector<double> data;
    node["data"] >> data;
    int r = rows, c = cols;
    if (!node["rows"].empty()) node["rows"] >> r;
    if (!node["cols"].empty()) node["cols"] >> c;
    if (r != rows || c != cols || data.size() != static_cast<std::size_t>(rows * cols)) {
      throw std::runtime_error("stereo calibration " + file + ": '" + key + "' must be " +
                               std::to_string(rows) + "x" + std::to_string(cols) + " (has " +
                               std::to_string(data.size()) + " values)");
    }
    m = cv::Mat(rows, cols, CV_64F);
    for (int i = 0; i < rows * cols; ++i) m.at<double>(i / cols, i % cols) = data[i];
  } else {
    node >> m;
    if (m.rows != rows || m.cols != cols) {
      throw std::runtime_error("stereo calibration " + file + ": '" + key + "' must be a " +
                               std::to_string(rows) + "x" + std::to_string(cols) + " matrix");
    }
    m.convertTo(m, CV_64F);
  }
  for (int i = 0; i < rows * cols; ++i) {
    if (!std::isfinite(m.at<double>(i / cols, i % cols))) {
      throw std::runtime_error("stereo calibration " + file + ": '" + key + "' is not finite");
    }
  }
  return m;
}

int readInt(const cv::FileStorage& fs, const std::string& file, const std::string& key) {
  const cv::FileNode node = fs[key];
  if (node.empty() || !node.isInt()) {
    throw std::runtime_error("stereo calibration " + file + ": no integer '" + key + "'");
  }
  return static_cast<int>(node);
}

}  // namespace

StereoCalibration loadStereoCalibrationYaml(const std::string& left_yaml,
                                            const std::string& right_yaml) {
  StereoCalibration c;
  try {
    cv::FileStorage left = openCheckedYaml(left_yaml, "stereo calibration");
    cv::FileStorage right = openCheckedYaml(right_yaml, "stereo calibration");
    c.width = readInt(left, left_yaml, "image_width");
    c.height = readInt(left, left_yaml, "image_height");
    const int rw = readInt(right, right_yaml, "image_width");
    const int rh = readInt(right, right_yaml, "image_height");
    if (rw != c.width || rh != c.height) {
      throw std::runtime_error("stereo calibration " + right_yaml + ": image size " +
                               std::to_string(rw) + "x" + std::to_string(rh) +
                               " differs from the left one");
    }
    // A rectified left image follows its projection matrix; fall back on the camera matrix.
    const cv::Mat k = left["projection_matrix"].empty()
                          ? readMatrix(left, left_yaml, "camera_matrix", 3, 3)
                          : readMatrix(left, left_yaml, "projection_matrix", 3, 4);
    c.fx_px = k.at<double>(0, 0);
    c.fy_px = k.at<double>(1, 1);
    c.cx_px = k.at<double>(0, 2);
    c.cy_px = k.at<double>(1, 2);
    const cv::Mat p = readMatrix(right, right_yaml, "projection_matrix", 3, 4);
    if (!(p.at<double>(0, 0) > 0)) {
      throw std::runtime_error("stereo calibration " + right_yaml +
                               ": projection_matrix has no focal length");
    }
    c.baseline_m = -p.at<double>(0, 3) / p.at<double>(0, 0);
  } catch (const cv::Exception& e) {
    throw std::runtime_error("stereo calibration " + left_yaml + " / " + right_yaml + ": " + e.err);
  }
  try {
    c.validate();
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error("stereo calibration " + left_yaml + " / " + right_yaml + ": " +
                             e.what());
  }
  return c;
}

}  // namespace upd::mrpt_bridge
