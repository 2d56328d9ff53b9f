#include "upd/core/point_cloud.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "upd/core/openmp.h"
#include "upd/core/vector_clones.h"

#include "preprocess_internal.h"

namespace upd::core {

namespace {
// out = r * p + t for n points; out may be the input arrays themselves (in place): a point's
// coordinates are read before its own are written, and `simd` states that the points do not
// depend on one another (no run-time alias check, which would send the in-place call to a scalar
// loop). The rotation and translation are plain local floats (firstprivate in the parallel loop):
// read through a matrix or a struct, they would be reloaded after every store.
void applyTransform(const Eigen::Matrix3f& r, const Eigen::Vector3f& t, std::size_t n,
                    const float* x, const float* y, const float* z, float* ox, float* oy,
                    float* oz) {
  const float r00 = r(0, 0), r01 = r(0, 1), r02 = r(0, 2), tx = t.x();
  const float r10 = r(1, 0), r11 = r(1, 1), r12 = r(1, 2), ty = t.y();
  const float r20 = r(2, 0), r21 = r(2, 1), r22 = r(2, 2), tz = t.z();
#pragma omp parallel for simd schedule(static) if (n > 65536)
  for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n); ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const float a = x[i], b = y[i], c = z[i];
    ox[i] = r00 * a + r01 * b + r02 * c + tx;
    oy[i] = r10 * a + r11 * b + r12 * c + ty;
    oz[i] = r20 * a + r21 * b + r22 * c + tz;
  }
}

// Each thread of the team copies its static share of the colour arrays (none when absent).
void copyColour(const PointCloud& in, PointCloud& out) {
  out.r.resize(in.r.size()), out.g.resize(in.g.size()), out.b.resize(in.b.size());
  const std::size_t n = in.r.size();
  if (n == 0 || in.g.size() != n || in.b.size() != n) {
    out.r = in.r, out.g = in.g, out.b = in.b;
    return;
  }
#pragma omp parallel if (n > 65536)
  {
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    const std::size_t begin = n * me / team, len = n * (me + 1) / team - begin;
    std::memcpy(out.r.data() + begin, in.r.data() + begin, len);
    std::memcpy(out.g.data() + begin, in.g.data() + begin, len);
    std::memcpy(out.b.data() + begin, in.b.data() + begin, len);
  }
}
// countFinite's loop: x - x is 0 for a finite x and NaN otherwise.
UPD_VECTOR_CLONES
std::size_t countFiniteIn(const float* __restrict x, const float* __restrict y,
                          const float* __restrict z, std::size_t n) {
  std::uint32_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    k += static_cast<std::uint32_t>(static_cast<int>(x[i] - x[i] == 0.f) &
                                    static_cast<int>(y[i] - y[i] == 0.f) &
                                    static_cast<int>(z[i] - z[i] == 0.f));
  }
  return k;
}

}  // namespace

std::size_t countFinite(const PointCloud& cloud, std::size_t begin, std::size_t end) {
  end = std::min(end, cloud.size());
  return begin < end ? countFiniteIn(cloud.x.data() + begin, cloud.y.data() + begin,
                                     cloud.z.data() + begin, end - begin)
                     : 0;
}

std::size_t PointCloud::countFinite() const { return core::countFinite(*this, 0, size()); }

std::size_t firstFinite(const PointCloud& cloud, std::size_t from) {
  constexpr std::size_t kBlock = 256;
  const std::size_t n = cloud.size();
  for (std::size_t b = from; b < n; b += kBlock) {
    if (countFinite(cloud, b, b + kBlock) == 0) continue;
    while (!cloud.isFinite(b)) ++b;
    return b;
  }
  return n;
}

void detail::copyAllButPoints(const PointCloud& in, PointCloud& out) {
  const std::size_t n = in.size();
  out.x.resize(n), out.y.resize(n), out.z.resize(n);
  copyColour(in, out);
  out.width = in.width;
  out.height = in.height;
  out.sensor_origin = in.sensor_origin;
}

std::size_t copyCloud(const PointCloud& in, PointCloud& out) {
  if (&out == &in) return in.countFinite();
  const std::size_t n = in.size();
  detail::copyAllButPoints(in, out);
  const float *x = in.x.data(), *y = in.y.data(), *z = in.z.data();
  float *ox = out.x.data(), *oy = out.y.data(), *oz = out.z.data();
  std::size_t finite = 0;
  // The same static split as applyTransform and the stages after it.
#pragma omp parallel for schedule(static) if (n > 65536) reduction(+ : finite)
  for (std::ptrdiff_t ii = 0; ii < static_cast<std::ptrdiff_t>(n); ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    ox[i] = x[i], oy[i] = y[i], oz[i] = z[i];
    finite += x[i] * 0.f + y[i] * 0.f + z[i] * 0.f == 0.f ? 1 : 0;  // as countFinite
  }
  return finite;
}

namespace {
// out's points and sensor origin = transform * in's (out may be in: in place). Its buffers
// must hold in's points.
void movePoints(const PointCloud& in, const Eigen::Isometry3d& transform, PointCloud& out) {
  const Eigen::Matrix3f r = transform.linear().cast<float>();
  const Eigen::Vector3f t = transform.translation().cast<float>();
  applyTransform(r, t, in.size(), in.x.data(), in.y.data(), in.z.data(), out.x.data(),
                 out.y.data(), out.z.data());
  out.sensor_origin = r * in.sensor_origin + t;
}
}  // namespace

void transformCloud(const PointCloud& cloud, const Eigen::Isometry3d& transform, PointCloud& out) {
  if (&out == &cloud) throw std::invalid_argument("transformCloud: out must not be the input");
  const std::size_t n = cloud.size();
  out.x.resize(n), out.y.resize(n), out.z.resize(n);
  copyColour(cloud, out);
  out.width = cloud.width;
  out.height = cloud.height;
  movePoints(cloud, transform, out);
}

PointCloud transformCloud(const PointCloud& cloud, const Eigen::Isometry3d& transform) {
  PointCloud out;
  transformCloud(cloud, transform, out);
  return out;
}

void transformInPlace(PointCloud& cloud, const Eigen::Isometry3d& transform) {
  movePoints(cloud, transform, cloud);
}

void rotateVectors(const Eigen::Matrix3f& rotation, std::size_t n, float* x, float* y, float* z) {
  applyTransform(rotation, Eigen::Vector3f::Zero(), n, x, y, z, x, y, z);
}

}  // namespace upd::core
