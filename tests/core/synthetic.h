// Small synthetic clouds for the core property tests (fixed seeds).
#pragma once

#include "upd/core/point_cloud.h"

#include <Eigen/Geometry>

#include <random>

namespace upd::test {

/// A square plane z = 0 of side size_m sampled every spacing_m, then rotated and translated.
inline core::PointCloud makePlane(double size_m, double spacing_m,
                            const Eigen::Isometry3d& pose = Eigen::Isometry3d::Identity()) {
  core::PointCloud c;
  const int n = static_cast<int>(std::lround(size_m / spacing_m)) + 1;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const Eigen::Vector3d p = pose * Eigen::Vector3d(i * spacing_m - 0.5 * size_m,
                                                       j * spacing_m - 0.5 * size_m, 0.0);
      c.push_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                  static_cast<float>(p.z()));
    }
  }
  c.sensor_origin = (pose * Eigen::Vector3d(0, 0, 2)).cast<float>();
  return c;
}

/// Uniform random points in a box with a bumpy surface: irregular density for search tests.
inline core::PointCloud makeRandomCloud(std::size_t n, std::uint32_t seed, float extent = 2.f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-extent, extent);
  std::normal_distribution<float> g(0.f, 0.05f);
  core::PointCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    const float x = u(rng), y = u(rng);
    c.push_back(x, y, 0.2f * std::sin(2.f * x) * std::cos(3.f * y) + g(rng));
  }
  return c;
}

inline core::PointCloud transformed(const core::PointCloud& in, const Eigen::Isometry3d& T) {
  core::PointCloud out = in;
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (!in.isFinite(i)) continue;
    const Eigen::Vector3d p = T * in.point(i).cast<double>();
    out.x[i] = static_cast<float>(p.x());
    out.y[i] = static_cast<float>(p.y());
    out.z[i] = static_cast<float>(p.z());
  }
  out.sensor_origin = (T * in.sensor_origin.cast<double>()).cast<float>();
  return out;
}

}  // namespace upd::test
