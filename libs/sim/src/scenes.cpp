#include "upd/sim/scenes.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <utility>

namespace upd::sim {

namespace sg = scene_geometry;

void SceneParams::validate() const {
  // The lower bound keeps a 3 x 3 m scene below ~10 million points.
  core::requireParam(std::isfinite(spacing_m) && spacing_m >= 0.001 && spacing_m <= 0.5, "SceneParams",
               "spacing_m", spacing_m, "must be in [0.001, 0.5]");
  core::requireParam(std::isfinite(noise_m) && noise_m >= 0, "SceneParams", "noise_m", noise_m,
               "must be >= 0");
  core::requireParam(seed >= 0, "SceneParams", "seed", seed, "must be >= 0");
}

std::vector<std::string> sceneNames() {
  return {"corner", "ramp", "step", "stairs", "ditch", "rocks"};
}

namespace {

std::string validNames() {
  std::string out;
  for (const std::string& n : sceneNames()) out += (out.empty() ? "" : ", ") + n;
  return out;
}

Scene cornerScene(double spacing_m) {
  const int n = static_cast<int>(std::floor(sg::kCornerSide_m / spacing_m + 1e-9));
  Scene s;
  s.name = "corner";
  s.cloud.reserve(static_cast<std::size_t>(n + 1) * (2 * n + 1));
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = i * spacing_m;
      s.cloud.push_back(static_cast<float>(x), static_cast<float>(j * spacing_m), 0.f);
      s.truth.push_back(x <= sg::kCornerEdgeBand_m + 1e-9 ? core::Label::NonTraversable
                                                          : core::Label::Traversable);
    }
  }
  for (int k = 1; k <= n; ++k) {
    for (int j = 0; j <= n; ++j) {
      s.cloud.push_back(0.f, static_cast<float>(j * spacing_m), static_cast<float>(k * spacing_m));
      s.truth.push_back(core::Label::NonTraversable);
    }
  }
  s.cloud.sensor_origin = Eigen::Vector3f(1.5f, 0.5f, 1.0f);
  return s;
}

Rock sceneRock(double x, double y, double rx, double ry, double h, double yaw = 0.0) {
  return Rock{{x, y}, rx, ry, h, yaw};  // centre, radii, height, yaw
}

Eigen::Vector3f sensorOrigin(const std::string& name) {
  if (name == "ditch" || name == "rocks") return {0.f, 0.f, 3.f};
  return {-2.5f, 0.f, 2.f};
}

}  // namespace

Terrain makeSceneTerrain(const std::string& name) {
  const Eigen::Vector2d lo(-1.5, -1.5), hi(1.5, 1.5);
  if (name == "ramp") {
    Terrain t(lo, {3.5, 1.5});
    Ramp r;
    r.start_xy = {0.0, 0.0};
    r.yaw_rad = 0.0;
    r.slope_rad = sg::kRampSlope_rad;
    r.width_m = sg::kRampWidth_m;
    r.height_m = sg::kRampLength_m * std::tan(sg::kRampSlope_rad);
    r.platform_length_m = sg::kRampPlatform_m;
    t.add(r);
    return t;
  }
  if (name == "step") {
    Terrain t(lo, hi);
    Box b;  // reaches past the extent on three sides: only the riser at x = 0 is inside
    b.center_xy = {1.25, 0.0};
    b.length_m = 2.5;
    b.width_m = 4.0;
    b.height_m = sg::kStepHeight_m;
    t.add(b);
    return t;
  }
  if (name == "stairs") {
    Terrain t(lo, hi);
    Stairs st;
    st.start_xy = {0.0, 0.0};
    st.width_m = 4.0;
    st.steps = sg::kStairsSteps;
    st.rise_m = sg::kStairsRise_m;
    st.run_m = sg::kStairsRun_m;
    st.top_length_m = 1.5;
    t.add(st);
    return t;
  }
  if (name == "ditch") {
    Terrain t(lo, hi);
    Ditch d;
    d.center_xy = {0.0, 0.0};
    d.yaw_rad = 0.5 * 3.14159265358979323846;  // length along y, width along x
    d.length_m = 4.0;
    d.width_m = sg::kDitchWidth_m;
    d.depth_m = sg::kDitchDepth_m;
    t.add(d);
    return t;
  }
  if (name == "rocks") {
    Terrain t(lo, hi);
    Roughness rough;
    rough.rms_height_m = 0.005;
    rough.wavelength_m = 0.4;
    rough.seed = 3;
    t.setRoughness(rough);
    t.add(sceneRock(-0.6, -0.5, 0.25, 0.25, 0.20))
        .add(sceneRock(0.5, 0.4, 0.26, 0.22, 0.22, 0.5))
        .add(sceneRock(0.6, -0.8, 0.20, 0.20, 0.25))
        .add(sceneRock(-0.7, 0.8, 0.22, 0.22, 0.20))
        .add(sceneRock(0.0, 0.0, 0.12, 0.12, 0.03))
        .add(sceneRock(-0.1, 1.0, 0.10, 0.10, 0.04));
    return t;
  }
  if (name == "corner") {
    throw std::invalid_argument("scene 'corner' is not a height field: it has no terrain");
  }
  throw std::invalid_argument("unknown scene '" + name + "'; valid names: " + validNames());
}

Scene makeScene(const std::string& name, const SceneParams& params) {
  params.validate();
  Scene s;
  if (name == "corner") {
    s = cornerScene(params.spacing_m);
  } else {
    const Terrain terrain = makeSceneTerrain(name);  // throws for unknown names
    SurfaceSamples samples = terrain.sampleSurface(params.spacing_m);
    s.name = name;
    s.cloud = std::move(samples.cloud);
    s.truth = std::move(samples.truth);
    s.cloud.sensor_origin = sensorOrigin(name);
  }
  if (params.noise_m > 0) {
    std::mt19937 rng(static_cast<std::uint32_t>(params.seed));
    std::normal_distribution<double> noise(0.0, params.noise_m);
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
      s.cloud.x[i] = static_cast<float>(s.cloud.x[i] + noise(rng));
      s.cloud.y[i] = static_cast<float>(s.cloud.y[i] + noise(rng));
      s.cloud.z[i] = static_cast<float>(s.cloud.z[i] + noise(rng));
    }
  }
  return s;
}

}  // namespace upd::sim
