// Pinhole depth cameras: intrinsics, depth images and their back-projection to organized clouds.
//
// Frames: a depth image is in the camera-optical frame (x right, y down, z forward along the
// optical axis), the convention of OpenNI, PCL and OpenCV. depth_m is the z coordinate (not the
// ray length); 0 or NaN marks an invalid pixel.
#pragma once

#include "upd/core/point_cloud.h"

#include <vector>

namespace upd::core {

struct CameraIntrinsics {
  int width = 640;  ///< [px]
  int height = 480;  ///< [px]
  double fx = 525.0;  ///< focal length [px]
  double fy = 525.0;  ///< focal length [px]
  double cx = 319.5;  ///< principal point [px]
  double cy = 239.5;  ///< principal point [px]

  void validate() const;
};

struct DepthImage {
  int width = 0, height = 0;
  std::vector<float> depth_m;  ///< row-major, width * height; 0 or NaN = invalid [m]

  float at(int u, int v) const { return depth_m[static_cast<std::size_t>(v) * width + u]; }
};

/// Back-projects every pixel: an organized width x height cloud in the camera-optical frame
/// with the sensor origin at 0; invalid pixels become NaN points.
PointCloud depthToCloud(const DepthImage& depth, const CameraIntrinsics& K);

/// The same into cloud, whose buffers are reused (a frame loop allocates nothing once warm).
void depthToCloud(const DepthImage& depth, const CameraIntrinsics& K, PointCloud& cloud);

}  // namespace upd::core
