#include "upd/core/camera.h"

#include "upd/core/params.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace upd::core {

void CameraIntrinsics::validate() const {
  requireParam(width > 0, "CameraIntrinsics", "width", width, "must be > 0");
  requireParam(height > 0, "CameraIntrinsics", "height", height, "must be > 0");
  requireParam(std::isfinite(fx) && fx > 0, "CameraIntrinsics", "fx", fx, "must be > 0");
  requireParam(std::isfinite(fy) && fy > 0, "CameraIntrinsics", "fy", fy, "must be > 0");
  requireParam(std::isfinite(cx), "CameraIntrinsics", "cx", cx, "must be finite");
  requireParam(std::isfinite(cy), "CameraIntrinsics", "cy", cy, "must be finite");
}

PointCloud depthToCloud(const DepthImage& depth, const CameraIntrinsics& K) {
  PointCloud cloud;
  depthToCloud(depth, K, cloud);
  return cloud;
}

void depthToCloud(const DepthImage& depth, const CameraIntrinsics& K, PointCloud& cloud) {
  K.validate();
  if (depth.width != K.width || depth.height != K.height ||
      depth.depth_m.size() != static_cast<std::size_t>(depth.width) * depth.height) {
    throw std::invalid_argument("depth image is " + std::to_string(depth.width) + "x" +
                                std::to_string(depth.height) + " but the intrinsics are " +
                                std::to_string(K.width) + "x" + std::to_string(K.height));
  }
  // Every pixel is written (a point or NaN), so the buffers are resized, not filled.
  const auto n = static_cast<std::size_t>(depth.width) * depth.height;
  cloud.resize(n, false);
  cloud.width = depth.width, cloud.height = depth.height;
  cloud.sensor_origin.setZero();
  const float inv_fx = static_cast<float>(1.0 / K.fx), inv_fy = static_cast<float>(1.0 / K.fy);
  const float cx = static_cast<float>(K.cx), cy = static_cast<float>(K.cy);
  const float nan = std::numeric_limits<float>::quiet_NaN();
#pragma omp parallel for schedule(static)
  for (int v = 0; v < depth.height; ++v) {
    for (int u = 0; u < depth.width; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * depth.width + u;
      const float d = depth.depth_m[i];
      const bool valid = d > 0.f && d <= std::numeric_limits<float>::max();
      cloud.x[i] = valid ? (static_cast<float>(u) - cx) * d * inv_fx : nan;
      cloud.y[i] = valid ? (static_cast<float>(v) - cy) * d * inv_fy : nan;
      cloud.z[i] = valid ? d : nan;
    }
  }
}

}  // namespace upd::core
