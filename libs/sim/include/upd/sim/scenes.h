// The paper's synthetic experiments as labelled point clouds, to test and score the UPD against
// an exact ground truth (Bellone & Reina 2013, section 6: the 90 deg corner, the ramp, steps).
//
// Every scene is in a z-up world frame (metres) with a per-point truth label. Apart from the
// corner, each scene is a Terrain (terrain.h) sampled by Terrain::sampleSurface: a grid every
// spacing_m over the extent plus the vertical faces, labelled by Terrain::truthAt (default
// TruthParams: 25 deg, 0.05 m step, 0.05 m band). The geometry, so tests can select regions:
//
//  corner  Exactly the paper's corner: floor z = 0 for x, y in [0, 1] and wall x = 0 for
//          y in [0, 1], z in (0, 1], sampled at multiples of spacing_m (n = floor(1/spacing_m)
//          steps per side): (n+1)^2 floor points then (n+1) n wall points, so the edge
//          (x = 0, z = 0) is sampled once, as floor. Truth: wall and floor with x <= 0.05
//          NonTraversable, the rest of the floor Traversable. Sensor at (1.5, 0.5, 1).
//  ramp    Extent x in [-1.5, 3.5], y in [-1.5, 1.5]. A 20 deg ramp 1.5 m wide (|y| <= 0.75)
//          starts at x = 0 (its concave lower border) and rises along +x for 2 m to
//          z = 2 tan 20 deg = 0.728 m at x = 2, then a platform at that height for x in
//          [2, 3]; ground z = 0 elsewhere. Traversable: ground, ramp body, lower border,
//          platform; NonTraversable: bands along the ramp and platform sides where they
//          stand > 0.05 m tall and along the platform's far edge (x = 3). Sensor (-2.5, 0, 2).
//  step    Extent [-1.5, 1.5]^2. A 0.15 m step up at x = 0 across the whole scene (z = 0.15
//          for x >= 0). NonTraversable: |x| <= 0.05 and the riser. Sensor (-2.5, 0, 2).
//  stairs  Extent [-1.5, 1.5]^2. Three steps up along +x across the whole scene: 0.15 m rise,
//          0.3 m run, risers at x = 0, 0.3, 0.6 (z = 0.45 beyond x = 0.6). NonTraversable:
//          within 0.05 m of a riser. Sensor (-2.5, 0, 2).
//  ditch   Extent [-1.5, 1.5]^2. A ditch 0.5 m wide (|x| <= 0.25), 0.3 m deep, across the
//          whole scene along y. NonTraversable: |x| <= 0.30 (floor, walls, rims). Sensor
//          (0, 0, 3).
//  rocks   Extent [-1.5, 1.5]^2. Rough ground (RMS 5 mm, 0.4 m wavelength) with four rocks
//          0.2-0.25 m high, 0.2-0.26 m in radius (NonTraversable with a 0.05 m band) and two
//          3-4 cm pebbles (Traversable); makeSceneTerrain("rocks").rocks() lists them.
//          Sensor (0, 0, 3).
//
// The sensor origin (PointCloud::sensor_origin) faces the vertical surfaces so normals
// oriented towards it point out of the walls.
#pragma once

#include "upd/core/params.h"
#include "upd/core/point_cloud.h"
#include "upd/sim/terrain.h"

#include <cstdint>
#include <string>
#include <vector>

namespace upd::sim {

/// Geometry constants of the scenes, as documented above.
namespace scene_geometry {
constexpr double kCornerSide_m = 1.0;
constexpr double kCornerEdgeBand_m = 0.05;
constexpr double kRampSlope_rad = 20.0 * core::kDegToRad;
constexpr double kRampLength_m = 2.0;    ///< horizontal, from x = 0
constexpr double kRampWidth_m = 1.5;     ///< centred on y = 0
constexpr double kRampPlatform_m = 1.0;  ///< flat top beyond x = kRampLength_m
constexpr double kStepHeight_m = 0.15;
constexpr double kStairsRise_m = 0.15;
constexpr double kStairsRun_m = 0.3;
constexpr int kStairsSteps = 3;
constexpr double kDitchWidth_m = 0.5;  ///< centred on x = 0
constexpr double kDitchDepth_m = 0.3;
}  // namespace scene_geometry

struct Scene {
  std::string name;
  core::PointCloud cloud;
  std::vector<core::Label> truth;                       ///< one per point of cloud
  Eigen::Vector3f up = Eigen::Vector3f::UnitZ();  ///< gravity-up in the cloud frame (unit)
};

struct SceneParams {
  double spacing_m = 0.01;  ///< sampling grid step [m]
  double noise_m = 0.0;     ///< std dev of the Gaussian noise added to each coordinate [m]
  int seed = 1;             ///< noise seed (>= 0)

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("spacing_m", spacing_m, "grid step of the synthetic scenes [m] (0.001 .. 0.5)");
    v("noise_m", noise_m, "std dev of Gaussian noise added to each coordinate [m]");
    v("seed", seed, "random seed of the noise");
  }
};

/// "corner", "ramp", "step", "stairs", "ditch", "rocks".
std::vector<std::string> sceneNames();

/// The terrain a scene samples (every scene but "corner", which is not a height field).
/// Throws std::invalid_argument for "corner" or an unknown name.
Terrain makeSceneTerrain(const std::string& name);

/// The named scene; with noise_m > 0 every coordinate of every point gets independent
/// N(0, noise_m^2) noise from a generator seeded with seed (the truth is not changed).
/// Throws std::invalid_argument listing the valid names, or naming the bad parameter.
Scene makeScene(const std::string& name, const SceneParams& params = SceneParams{});

}  // namespace upd::sim
