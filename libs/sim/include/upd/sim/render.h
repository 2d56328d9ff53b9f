// A simulated depth camera over a Terrain: depth images and labelled organized clouds as a
// Kinect would give them, for tests of the UPD on sensor-like data and for the robot simulator.
//
// Every pixel casts the ray of the pinhole model (camera-optical frame: x right, y down,
// z forward) into the terrain (Terrain::raycast: vertical faces are hit as vertical surfaces).
// The image stores the z-depth of the hit. Noise follows the Kinect axial model of Khoshelham
// & Elberink 2012: Gaussian along z with sigma = sigma_coeff_per_m * z^2, then rounding to the
// millimetre. A pixel is invalid (0) when its ray hits nothing or the noisy depth is outside
// [min_range_m, max_range_m]. Each image row draws from its own generator seeded by (seed, row),
// so the image does not depend on the number of threads.
#pragma once

#include "upd/core/camera.h"
#include "upd/core/params.h"
#include "upd/sim/scenes.h"
#include "upd/sim/terrain.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <string>

namespace upd::sim {

struct DepthNoise {
  double sigma_coeff_per_m = 1.2e-3;  ///< axial sigma = coeff * z^2 [1/m]; 0 = noise-free
  double max_range_m = 8.0;           ///< farther z-depths are invalid [m]
  double min_range_m = 0.4;           ///< nearer z-depths are invalid [m]
  bool quantize_mm = true;            ///< round depths to the millimetre

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("sigma_coeff_per_m", sigma_coeff_per_m, "axial noise sigma = coeff * z^2 [1/m]");
    v("max_range_m", max_range_m, "farther depths are invalid [m]");
    v("min_range_m", min_range_m, "nearer depths are invalid [m]");
    v("quantize_mm", quantize_mm, "round depths to the millimetre");
  }
};

/// The pose of a camera at eye looking at target (optical axis towards it, image rows down
/// against up_world). Throws std::invalid_argument when target == eye or the viewing direction
/// is parallel to up_world.
Eigen::Isometry3d cameraPoseLookingAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                                      const Eigen::Vector3d& up_world = Eigen::Vector3d::UnitZ());

/// Renders the z-depth image seen from pose_world_camera (camera-optical to world).
core::DepthImage renderDepth(const Terrain& terrain, const Eigen::Isometry3d& pose_world_camera,
                       const core::CameraIntrinsics& K, const DepthNoise& noise, std::uint32_t seed);

/// A rendered view: the depth image and, as a Scene, its organized cloud in the camera-optical
/// frame (sensor origin 0, invalid pixels NaN) with per-pixel truth (Terrain::truthAt of the
/// exact hit; Unknown for invalid pixels) and the world up expressed in the camera frame.
struct RenderedScene {
  core::DepthImage depth;
  Scene scene;
  Eigen::Isometry3d pose_world_camera = Eigen::Isometry3d::Identity();
};

/// Renders as renderDepth (same image for the same seed) and labels every pixel.
RenderedScene renderScene(const Terrain& terrain, const Eigen::Isometry3d& pose_world_camera,
                          const core::CameraIntrinsics& K, const DepthNoise& noise, std::uint32_t seed,
                          const std::string& name = "rendered");

}  // namespace upd::sim
