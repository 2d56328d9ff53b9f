#include "upd/sim/render.h"

#include <cmath>
#include <random>
#include <stdexcept>

namespace upd::sim {

void DepthNoise::validate() const {
  core::requireParam(std::isfinite(sigma_coeff_per_m) && sigma_coeff_per_m >= 0, "DepthNoise",
               "sigma_coeff_per_m", sigma_coeff_per_m, "must be >= 0");
  core::requireParam(std::isfinite(min_range_m) && min_range_m >= 0, "DepthNoise", "min_range_m",
               min_range_m, "must be >= 0");
  core::requireParam(std::isfinite(max_range_m) && max_range_m > min_range_m, "DepthNoise", "max_range_m",
               max_range_m, "must be finite and > min_range_m");
}

Eigen::Isometry3d cameraPoseLookingAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                                      const Eigen::Vector3d& up_world) {
  const Eigen::Vector3d forward = target - eye;
  if (!eye.allFinite() || !target.allFinite() || !(forward.norm() > 0)) {
    throw std::invalid_argument("cameraPoseLookingAt: target must be finite and differ from eye");
  }
  const Eigen::Vector3d z = forward.normalized();
  const Eigen::Vector3d right = z.cross(up_world);
  if (!(right.norm() > 1e-9 * up_world.norm())) {
    throw std::invalid_argument(
        "cameraPoseLookingAt: the viewing direction is parallel to up_world");
  }
  const Eigen::Vector3d x = right.normalized();
  const Eigen::Vector3d y = z.cross(x);  // image rows go down, against up_world
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear().col(0) = x;
  pose.linear().col(1) = y;
  pose.linear().col(2) = z;
  pose.translation() = eye;
  return pose;
}

namespace {

// Renders the depth image; when truth is given, labels every pixel from its exact hit.
core::DepthImage render(const Terrain& terrain, const Eigen::Isometry3d& pose_world_camera,
                  const core::CameraIntrinsics& K, const DepthNoise& noise, std::uint32_t seed,
                  std::vector<core::Label>* truth) {
  K.validate();
  noise.validate();
  if (!pose_world_camera.matrix().allFinite()) {
    throw std::invalid_argument("render: pose_world_camera must be finite");
  }
  core::DepthImage img;
  img.width = K.width;
  img.height = K.height;
  const std::size_t n = static_cast<std::size_t>(K.width) * K.height;
  img.depth_m.assign(n, 0.f);
  if (truth) truth->assign(n, core::Label::Unknown);

  const Eigen::Matrix3d R = pose_world_camera.linear();
  const Eigen::Vector3d eye = pose_world_camera.translation();
  const Eigen::Vector3d optical_axis = R.col(2);

#pragma omp parallel for schedule(dynamic, 4)
  for (int v = 0; v < K.height; ++v) {
    // One generator per row (splitmix-style mix of seed and row): thread-count independent.
    std::uint64_t mix = (static_cast<std::uint64_t>(seed) << 32) + static_cast<std::uint64_t>(v);
    mix = (mix ^ (mix >> 30)) * 0xbf58476d1ce4e5b9ULL;
    mix = (mix ^ (mix >> 27)) * 0x94d049bb133111ebULL;
    std::mt19937 rng(static_cast<std::uint32_t>(mix ^ (mix >> 31)));
    std::normal_distribution<double> unit(0.0, 1.0);
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray_c((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
      const Eigen::Vector3d ray_w = R * ray_c;
      // z-depth = ray length / |ray_c|: casting to max_range * |ray_c| finds every z in range.
      const auto hit = terrain.raycast(eye, ray_w, noise.max_range_m * ray_c.norm());
      if (!hit) continue;
      double z = (*hit - eye).dot(optical_axis);
      if (noise.sigma_coeff_per_m > 0) z += noise.sigma_coeff_per_m * z * z * unit(rng);
      if (noise.quantize_mm) z = std::round(z * 1000.0) / 1000.0;
      if (!(z >= noise.min_range_m && z <= noise.max_range_m)) continue;
      const std::size_t i = static_cast<std::size_t>(v) * K.width + u;
      img.depth_m[i] = static_cast<float>(z);
      if (truth) (*truth)[i] = terrain.truthAt(hit->x(), hit->y());
    }
  }
  return img;
}

}  // namespace

core::DepthImage renderDepth(const Terrain& terrain, const Eigen::Isometry3d& pose_world_camera,
                       const core::CameraIntrinsics& K, const DepthNoise& noise, std::uint32_t seed) {
  return render(terrain, pose_world_camera, K, noise, seed, nullptr);
}

RenderedScene renderScene(const Terrain& terrain, const Eigen::Isometry3d& pose_world_camera,
                          const core::CameraIntrinsics& K, const DepthNoise& noise, std::uint32_t seed,
                          const std::string& name) {
  RenderedScene out;
  out.pose_world_camera = pose_world_camera;
  out.depth = render(terrain, pose_world_camera, K, noise, seed, &out.scene.truth);
  out.scene.name = name;
  out.scene.cloud = core::depthToCloud(out.depth, K);
  out.scene.up = (pose_world_camera.linear().transpose() * Eigen::Vector3d::UnitZ())
                     .normalized()
                     .cast<float>();
  return out;
}

}  // namespace upd::sim
