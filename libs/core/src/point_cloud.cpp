#include "upd/core/point_cloud.h"

#include <stdexcept>

namespace upd {

namespace {
// out = r * p + t for n points. The rotation and translation are plain local floats (firstprivate
// in the parallel loop): read through a matrix or a struct, they would be reloaded after every
// store (the compiler cannot rule out aliasing) and the loop would stay scalar.
void applyTransform(const Eigen::Matrix3f& r, const Eigen::Vector3f& t, std::size_t n,
                    const float* __restrict x, const float* __restrict y, const float* __restrict z,
                    float* __restrict ox, float* __restrict oy, float* __restrict oz) {
  const float r00 = r(0, 0), r01 = r(0, 1), r02 = r(0, 2), tx = t.x();
  const float r10 = r(1, 0), r11 = r(1, 1), r12 = r(1, 2), ty = t.y();
  const float r20 = r(2, 0), r21 = r(2, 1), r22 = r(2, 2), tz = t.z();
#pragma omp parallel for schedule(static) if (n > 65536)
  for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n); ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    ox[i] = r00 * x[i] + r01 * y[i] + r02 * z[i] + tx;
    oy[i] = r10 * x[i] + r11 * y[i] + r12 * z[i] + ty;
    oz[i] = r20 * x[i] + r21 * y[i] + r22 * z[i] + tz;
  }
}
}  // namespace

void transformCloud(const PointCloud& cloud, const Eigen::Isometry3d& transform, PointCloud& out) {
  if (&out == &cloud) throw std::invalid_argument("transformCloud: out must not be the input");
  const std::size_t n = cloud.size();
  out.x.resize(n), out.y.resize(n), out.z.resize(n);
  out.r = cloud.r, out.g = cloud.g, out.b = cloud.b;
  out.width = cloud.width;
  out.height = cloud.height;
  const Eigen::Matrix3f r = transform.linear().cast<float>();
  const Eigen::Vector3f t = transform.translation().cast<float>();
  applyTransform(r, t, n, cloud.x.data(), cloud.y.data(), cloud.z.data(), out.x.data(),
                 out.y.data(), out.z.data());
  out.sensor_origin = r * cloud.sensor_origin + t;
}

PointCloud transformCloud(const PointCloud& cloud, const Eigen::Isometry3d& transform) {
  PointCloud out;
  transformCloud(cloud, transform, out);
  return out;
}

void rotateVectors(const Eigen::Matrix3f& rotation, std::size_t n, const float* x, const float* y,
                   const float* z, float* out_x, float* out_y, float* out_z) {
  applyTransform(rotation, Eigen::Vector3f::Zero(), n, x, y, z, out_x, out_y, out_z);
}

}  // namespace upd
