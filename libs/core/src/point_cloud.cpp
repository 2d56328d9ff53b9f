#include "upd/core/point_cloud.h"

#include <stdexcept>

namespace upd {

namespace {
// Rotation and translation as plain floats: read through an Eigen matrix inside the loop they
// would be reloaded after every store (the compiler cannot rule out aliasing) and the loop
// would stay scalar.
struct PlainTransform {
  float r00, r01, r02, r10, r11, r12, r20, r21, r22, tx, ty, tz;
  PlainTransform(const Eigen::Matrix3f& r, const Eigen::Vector3f& t)
      : r00(r(0, 0)),
        r01(r(0, 1)),
        r02(r(0, 2)),
        r10(r(1, 0)),
        r11(r(1, 1)),
        r12(r(1, 2)),
        r20(r(2, 0)),
        r21(r(2, 1)),
        r22(r(2, 2)),
        tx(t.x()),
        ty(t.y()),
        tz(t.z()) {}
  void apply(std::size_t n, const float* __restrict x, const float* __restrict y,
             const float* __restrict z, float* __restrict ox, float* __restrict oy,
             float* __restrict oz) const {
    const PlainTransform m = *this;  // locals: no reload after a store
#pragma omp parallel for schedule(static) if (n > 65536)
    for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n); ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      ox[i] = m.r00 * x[i] + m.r01 * y[i] + m.r02 * z[i] + m.tx;
      oy[i] = m.r10 * x[i] + m.r11 * y[i] + m.r12 * z[i] + m.ty;
      oz[i] = m.r20 * x[i] + m.r21 * y[i] + m.r22 * z[i] + m.tz;
    }
  }
};
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
  PlainTransform(r, t).apply(n, cloud.x.data(), cloud.y.data(), cloud.z.data(), out.x.data(),
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
  PlainTransform(rotation, Eigen::Vector3f::Zero()).apply(n, x, y, z, out_x, out_y, out_z);
}

}  // namespace upd
