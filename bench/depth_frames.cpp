#include "depth_frames.h"

#include <cmath>
#include <cstdint>

#include "upd/sim/render.h"
#include "upd/sim/robot.h"
#include "upd/sim/world_generator.h"

namespace upd::bench {

std::vector<core::DepthImage> renderFrames(int n, const core::CameraIntrinsics& K) {
  const sim::WorldSpec world = sim::makeWorld("mixed");
  sim::DepthNoise noise;
  noise.max_range_m = 5.0;
  std::vector<core::DepthImage> frames;
  for (int i = 0; i < n; ++i) {
    const double x = 0.5 + 0.05 * i;
    const Eigen::Isometry3d pose = sim::cameraPoseLookingAt({x, 0.3, 0.6}, {x + 3.5, -0.4, 0.0});
    frames.push_back(sim::renderDepth(world.terrain, pose, K, noise, 7 + i));
  }
  return frames;
}

mrpt::obs::CObservation3DRangeScan scanOf(const core::DepthImage& d) {
  mrpt::obs::CObservation3DRangeScan obs;
  obs.hasRangeImage = true;
  obs.rangeUnits = 1e-3f;
  obs.rangeImage.resize(static_cast<int>(d.height), static_cast<int>(d.width));
  for (int v = 0; v < d.height; ++v) {
    for (int u = 0; u < d.width; ++u) {
      const float z = d.depth_m[static_cast<std::size_t>(v) * d.width + u];
      obs.rangeImage(v, u) =
          std::isfinite(z) && z > 0 ? static_cast<std::uint16_t>(z * 1000.f + 0.5f) : 0;
    }
  }
  return obs;
}

}  // namespace upd::bench
