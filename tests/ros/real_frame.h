// The real RGB-D frame the ROS tests publish and record: RTAB-Map's sample depth image
// (16-bit PNG, millimetres) with its calibration (OpenCV YAML: camera_matrix, and
// local_transform, the camera-optical frame on base_link).
#pragma once

#include "upd/core/camera.h"

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <stdexcept>
#include <string>
#include <vector>

namespace upd::test {

struct RealFrame {
  core::DepthImage depth;
  core::CameraIntrinsics K;
  Eigen::Isometry3d pose_base_optical = Eigen::Isometry3d::Identity();
};

inline RealFrame loadRealFrame(const std::string& png, const std::string& yaml) {
  const cv::Mat img = cv::imread(png, cv::IMREAD_ANYDEPTH);
  if (img.empty() || img.type() != CV_16UC1) throw std::runtime_error(png + ": not a 16-bit PNG");
  RealFrame f;
  f.depth.width = img.cols;
  f.depth.height = img.rows;
  f.depth.depth_m.resize(static_cast<std::size_t>(img.cols) * img.rows);
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u)
      f.depth.depth_m[static_cast<std::size_t>(v) * img.cols + u] = img.at<std::uint16_t>(v, u) * 0.001f;
  cv::FileStorage fs(yaml, cv::FileStorage::READ);
  std::vector<double> k, t;
  fs["camera_matrix"]["data"] >> k;
  fs["local_transform"]["data"] >> t;
  if (k.size() != 9 || t.size() != 12) throw std::runtime_error(yaml + ": no calibration");
  f.K.width = static_cast<int>(fs["image_width"]);
  f.K.height = static_cast<int>(fs["image_height"]);
  f.K.fx = k[0];
  f.K.cx = k[2];
  f.K.fy = k[4];
  f.K.cy = k[5];
  Eigen::Matrix3d r;
  r << t[0], t[1], t[2], t[4], t[5], t[6], t[8], t[9], t[10];
  f.pose_base_optical.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
  f.pose_base_optical.translation() = Eigen::Vector3d(t[3], t[7], t[11]);
  return f;
}

}  // namespace upd::test
