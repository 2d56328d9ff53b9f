// The synthetic scenes and worlds: exact sampling, truth regions, noise, named worlds.
#include "upd/sim/robot.h"
#include "upd/sim/scenes.h"
#include "upd/sim/terrain.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <stdexcept>
#include <string>
#include <vector>

namespace core = upd::core;

namespace {

using upd::core::Label;
namespace sg = upd::sim::scene_geometry;

std::string thrownMessage(const std::function<void()>& fn) {
  try {
    fn();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(nothing thrown)";
}

std::size_t countLabel(const std::vector<core::Label>& labels, core::Label l) {
  std::size_t n = 0;
  for (core::Label x : labels) n += x == l ? 1 : 0;
  return n;
}

// ------------------------------------------------------------------------------ corner

TEST(CornerScene, HasExactlyTheDocumentedPoints) {
  const upd::sim::Scene s = upd::sim::makeScene("corner", {});
  ASSERT_EQ(s.cloud.size(), 101u * 101u + 101u * 100u);
  ASSERT_EQ(s.truth.size(), s.cloud.size());
  const std::size_t floor_points = 101u * 101u;
  for (std::size_t i = 0; i < floor_points; ++i) {
    ASSERT_EQ(s.cloud.z[i], 0.f) << i;
    ASSERT_GE(s.cloud.x[i], 0.f);
    ASSERT_LE(s.cloud.x[i], 1.f + 1e-6f);
  }
  for (std::size_t i = floor_points; i < s.cloud.size(); ++i) {
    ASSERT_EQ(s.cloud.x[i], 0.f) << i;
    ASSERT_GT(s.cloud.z[i], 0.f);
    ASSERT_LE(s.cloud.z[i], 1.f + 1e-6f);
  }
  // The shared edge is sampled once.
  std::size_t on_edge = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    on_edge += (s.cloud.x[i] == 0.f && s.cloud.z[i] == 0.f) ? 1 : 0;
  }
  EXPECT_EQ(on_edge, 101u);
  EXPECT_TRUE(s.cloud.sensor_origin.isApprox(Eigen::Vector3f(1.5f, 0.5f, 1.0f)));
  EXPECT_TRUE(s.up.isApprox(Eigen::Vector3f::UnitZ()));
}

TEST(CornerScene, SpacingThatDoesNotDivideTheSideStopsInside) {
  upd::sim::SceneParams p;
  p.spacing_m = 0.03;  // 33 steps of 0.03 m: last sample at 0.99
  const upd::sim::Scene s = upd::sim::makeScene("corner", p);
  EXPECT_EQ(s.cloud.size(), 34u * 34u + 34u * 33u);
}

TEST(CornerScene, TruthIsTheEdgeBandAndTheWall) {
  const upd::sim::Scene s = upd::sim::makeScene("corner", {});
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const bool wall = s.cloud.z[i] > 0.f;
    const bool band = s.cloud.x[i] <= sg::kCornerEdgeBand_m + 1e-6;
    const core::Label expected = (wall || band) ? core::Label::NonTraversable : core::Label::Traversable;
    ASSERT_EQ(s.truth[i], expected) << s.cloud.point(i).transpose();
  }
}

// ------------------------------------------------------------------------------ all scenes

TEST(Scenes, EveryNamedSceneHasBothLabelsAndNoUnknown) {
  ASSERT_EQ(upd::sim::sceneNames().size(), 6u);
  for (const std::string& name : upd::sim::sceneNames()) {
    SCOPED_TRACE(name);
    upd::sim::SceneParams p;
    p.spacing_m = 0.02;
    const upd::sim::Scene s = upd::sim::makeScene(name, p);
    EXPECT_EQ(s.name, name);
    ASSERT_EQ(s.truth.size(), s.cloud.size());
    EXPECT_EQ(s.cloud.countFinite(), s.cloud.size());
    EXPECT_GT(countLabel(s.truth, core::Label::Traversable), s.cloud.size() / 4);
    EXPECT_GT(countLabel(s.truth, core::Label::NonTraversable), 100u);
    EXPECT_EQ(countLabel(s.truth, core::Label::Unknown), 0u);
  }
}

TEST(Scenes, TerrainScenesAreAboutThreeMetresWide) {
  for (const std::string& name : upd::sim::sceneNames()) {
    if (name == "corner") continue;
    SCOPED_TRACE(name);
    const upd::sim::Terrain t = upd::sim::makeSceneTerrain(name);
    const Eigen::Vector2d size = t.maxXY() - t.minXY();
    EXPECT_GE(size.minCoeff(), 3.0);
    EXPECT_LE(size.maxCoeff(), 5.0);
  }
}

TEST(StepScene, HeightsTruthAndRiser) {
  const upd::sim::Scene s = upd::sim::makeScene("step", {});
  std::size_t riser = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const float x = s.cloud.x[i], z = s.cloud.z[i];
    const bool on_face = z > 1e-6f && z < sg::kStepHeight_m - 1e-6;
    if (on_face) {
      ASSERT_NEAR(x, 0.f, 1e-6f);
      ASSERT_EQ(s.truth[i], core::Label::NonTraversable);
      ++riser;
      continue;
    }
    ASSERT_NEAR(z, x < 0 ? 0.f : sg::kStepHeight_m, 1e-6) << x;
    if (std::abs(x) > 0.06f) {
      ASSERT_EQ(s.truth[i], core::Label::Traversable) << x;
    }
    if (std::abs(x) < 0.04f) {
      ASSERT_EQ(s.truth[i], core::Label::NonTraversable) << x;
    }
  }
  // 301 columns along y (|y| <= 1.5) of 14 points (z = 0.01 .. 0.14).
  EXPECT_EQ(riser, 301u * 14u);
}

TEST(RampScene, BodyFootAndGroundAreTraversableSidesAreNot) {
  const upd::sim::Scene s = upd::sim::makeScene("ramp", {});
  const double tan_slope = std::tan(sg::kRampSlope_rad);
  std::size_t body = 0, foot = 0, ground = 0, side = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const double x = s.cloud.x[i], y = s.cloud.y[i], z = s.cloud.z[i];
    const bool inside_width = std::abs(y) < 0.5 * sg::kRampWidth_m - 0.1;
    if (x > 0.2 && x < sg::kRampLength_m - 0.2 && inside_width) {
      ASSERT_NEAR(z, x * tan_slope, 1e-5);
      ASSERT_EQ(s.truth[i], core::Label::Traversable) << x << " " << y;
      ++body;
    } else if (std::abs(x) <= 0.02 && inside_width) {
      ASSERT_NEAR(z, std::max(0.0, x * tan_slope), 1e-5);
      ASSERT_EQ(s.truth[i], core::Label::Traversable) << "lower border " << x << " " << y;
      ++foot;
    } else if (x < -0.6) {
      ASSERT_EQ(z, 0.f);
      ASSERT_EQ(s.truth[i], core::Label::Traversable);
      ++ground;
    } else if (x > 0.5 && x < sg::kRampLength_m && std::abs(y) > 0.5 * sg::kRampWidth_m &&
               std::abs(y) < 0.5 * sg::kRampWidth_m + 0.04) {
      // The side of the ramp stands > 0.18 m tall here.
      ASSERT_EQ(s.truth[i], core::Label::NonTraversable) << x << " " << y;
      ++side;
    }
  }
  EXPECT_GT(body, 1000u);
  EXPECT_GT(foot, 100u);
  EXPECT_GT(ground, 1000u);
  EXPECT_GT(side, 100u);
}

TEST(StairsScene, TreadMiddlesTraversableRiserBandsNot) {
  const upd::sim::Scene s = upd::sim::makeScene("stairs", {});
  const upd::sim::Terrain t = upd::sim::makeSceneTerrain("stairs");
  std::size_t faces = 0, treads = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const double x = s.cloud.x[i], y = s.cloud.y[i], z = s.cloud.z[i];
    if (std::abs(z - t.heightAt(x, y)) > 1e-6) {  // a riser point
      ++faces;
      ASSERT_EQ(s.truth[i], core::Label::NonTraversable);
      continue;
    }
    double riser_dist = 1e9;
    for (int k = 0; k < sg::kStairsSteps; ++k) {
      riser_dist = std::min(riser_dist, std::abs(x - k * sg::kStairsRun_m));
    }
    if (riser_dist < 0.04) {
      ASSERT_EQ(s.truth[i], core::Label::NonTraversable) << x;
    }
    if (riser_dist > 0.06) {
      ASSERT_EQ(s.truth[i], core::Label::Traversable) << x;
      if (x > 0 && x < sg::kStairsSteps * sg::kStairsRun_m) ++treads;
    }
    const int step =
        x < 0 ? 0 : std::min(sg::kStairsSteps, 1 + static_cast<int>(x / sg::kStairsRun_m + 1e-9));
    ASSERT_NEAR(z, step * sg::kStairsRise_m, 1e-5) << x;
  }
  EXPECT_EQ(faces, 3u * 301u * 14u);  // three risers of 14 points per column
  EXPECT_GT(treads, 3u * 301u * 10u);
}

TEST(DitchScene, DitchAndRimsAreNonTraversable) {
  const upd::sim::Scene s = upd::sim::makeScene("ditch", {});
  const double half = 0.5 * sg::kDitchWidth_m;
  std::size_t walls = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const double x = s.cloud.x[i], z = s.cloud.z[i];
    if (z < -1e-6 && z > -sg::kDitchDepth_m + 1e-6) {
      ASSERT_NEAR(std::abs(x), half, 1e-6);
      ++walls;
    } else if (std::abs(x) < half - 1e-6) {
      ASSERT_NEAR(z, -sg::kDitchDepth_m, 1e-6);
    } else if (std::abs(x) > half + 1e-6) {
      ASSERT_EQ(z, 0.f);
    }
    if (std::abs(x) <= half + 0.049) {
      ASSERT_EQ(s.truth[i], core::Label::NonTraversable) << x;
    }
    if (std::abs(x) >= half + 0.051) {
      ASSERT_EQ(s.truth[i], core::Label::Traversable) << x;
    }
  }
  EXPECT_EQ(walls, 2u * 301u * 29u);  // two walls, z = -0.29 .. -0.01
}

TEST(RocksScene, RocksAreNonTraversablePebblesAndGroundAreNot) {
  const upd::sim::Scene s = upd::sim::makeScene("rocks", {});
  const upd::sim::Terrain t = upd::sim::makeSceneTerrain("rocks");
  ASSERT_FALSE(t.rocks().empty());
  for (const upd::sim::Rock& r : t.rocks()) {
    const core::Label at_top = t.truthAt(r.center_xy.x(), r.center_xy.y());
    EXPECT_NEAR(t.heightAt(r.center_xy.x(), r.center_xy.y()), r.height_m, 0.03);
    EXPECT_EQ(at_top,
              r.height_m > t.truthParams().max_step_m ? core::Label::NonTraversable : core::Label::Traversable)
        << r.center_xy.transpose();
  }
  // Rough ground: the height varies by millimetres away from the rocks, and stays traversable.
  double min_z = 1, max_z = -1;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const Eigen::Vector2d p(s.cloud.x[i], s.cloud.y[i]);
    bool near_rock = false;
    for (const upd::sim::Rock& r : t.rocks()) {
      near_rock |= (p - r.center_xy).norm() < std::max(r.radius_x_m, r.radius_y_m) + 0.1;
    }
    if (near_rock) continue;
    min_z = std::min(min_z, static_cast<double>(s.cloud.z[i]));
    max_z = std::max(max_z, static_cast<double>(s.cloud.z[i]));
    ASSERT_EQ(s.truth[i], core::Label::Traversable) << p.transpose();
  }
  EXPECT_GT(max_z - min_z, 0.01);
  EXPECT_LT(max_z - min_z, 0.05);
}

// ------------------------------------------------------------------------------ noise, params

TEST(Scenes, NoiseHasTheRequestedSigmaAndIsReproducible) {
  upd::sim::SceneParams clean;
  upd::sim::SceneParams noisy;
  noisy.noise_m = 0.01;
  noisy.seed = 5;
  const upd::sim::Scene a = upd::sim::makeScene("corner", clean);
  const upd::sim::Scene b = upd::sim::makeScene("corner", noisy);
  const upd::sim::Scene c = upd::sim::makeScene("corner", noisy);
  ASSERT_EQ(a.cloud.size(), b.cloud.size());
  double sum = 0, sum2 = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.cloud.size(); ++i) {
    const Eigen::Vector3f d = b.cloud.point(i) - a.cloud.point(i);
    for (int k = 0; k < 3; ++k) {
      sum += d[k];
      sum2 += d[k] * d[k];
      ++n;
    }
    ASSERT_EQ(b.cloud.point(i), c.cloud.point(i));  // same seed, same cloud
  }
  const double mean = sum / n;
  const double sigma = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 3 * 0.01 / std::sqrt(static_cast<double>(n)) + 1e-6);
  EXPECT_NEAR(sigma, 0.01, 0.01 * 0.03);
  EXPECT_EQ(a.truth, b.truth);  // noise leaves the truth alone

  noisy.seed = 6;
  const upd::sim::Scene other = upd::sim::makeScene("corner", noisy);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < b.cloud.size(); ++i)
    differ += b.cloud.point(i) != other.cloud.point(i);
  EXPECT_GT(differ, b.cloud.size() * 9 / 10);
}

TEST(Scenes, UnknownNameThrowsListingValidNames) {
  const std::string msg = thrownMessage([] { upd::sim::makeScene("volcano", {}); });
  for (const std::string& name : upd::sim::sceneNames())
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
  EXPECT_NE(msg.find("volcano"), std::string::npos);
  EXPECT_THROW(upd::sim::makeSceneTerrain("corner"), std::invalid_argument);
  EXPECT_THROW(upd::sim::makeSceneTerrain("volcano"), std::invalid_argument);
}

TEST(Scenes, BadParamsThrowNamingTheField) {
  upd::sim::SceneParams p;
  p.spacing_m = 0.0;
  EXPECT_NE(thrownMessage([&] { upd::sim::makeScene("corner", p); }).find("SceneParams.spacing_m"),
            std::string::npos);
  p.spacing_m = -0.01;
  EXPECT_NE(thrownMessage([&] { upd::sim::makeScene("ramp", p); }).find("SceneParams.spacing_m"),
            std::string::npos);
  p = {};
  p.noise_m = -0.001;
  EXPECT_NE(thrownMessage([&] { upd::sim::makeScene("corner", p); }).find("SceneParams.noise_m"),
            std::string::npos);
  p = {};
  p.seed = -1;
  EXPECT_NE(thrownMessage([&] { p.validate(); }).find("SceneParams.seed"), std::string::npos);
  EXPECT_NO_THROW(upd::sim::SceneParams{}.validate());
}

// ------------------------------------------------------------------------------ terrain

TEST(Terrain, PrimitivesHaveTheirHeights) {
  upd::sim::Terrain t({-5, -5}, {5, 5});
  upd::sim::Box box;
  box.center_xy = {2.0, 2.0};
  box.length_m = 1.0;
  box.width_m = 0.4;
  box.height_m = 0.2;
  box.yaw_rad = 90.0 * upd::core::kDegToRad;  // long along y
  upd::sim::Stairs st;
  st.start_xy = {-3.0, 0.0};
  st.steps = 2;
  st.rise_m = 0.1;
  st.run_m = 0.4;
  st.top_length_m = 0.5;
  upd::sim::Ditch d;
  d.center_xy = {0.0, -3.0};
  d.length_m = 2.0;
  d.width_m = 0.5;
  d.depth_m = 0.25;
  upd::sim::Rock r;
  r.center_xy = {3.0, -2.0};
  r.radius_x_m = 0.4;
  r.radius_y_m = 0.2;
  r.height_m = 0.3;
  t.add(box).add(st).add(d).add(r);

  EXPECT_DOUBLE_EQ(t.heightAt(2.0, 2.45), 0.2);  // inside along y
  EXPECT_DOUBLE_EQ(t.heightAt(2.45, 2.0), 0.0);  // outside across it
  EXPECT_DOUBLE_EQ(t.heightAt(-2.8, 0.0), 0.1);
  EXPECT_DOUBLE_EQ(t.heightAt(-2.4, 0.0), 0.2);   // on the second riser: the upper step
  EXPECT_DOUBLE_EQ(t.heightAt(-1.75, 0.0), 0.2);  // the top continues
  EXPECT_DOUBLE_EQ(t.heightAt(-1.65, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(t.heightAt(0.9, -3.0), -0.25);
  EXPECT_DOUBLE_EQ(t.heightAt(0.0, -3.3), 0.0);
  EXPECT_DOUBLE_EQ(t.heightAt(3.0, -2.0), 0.3);
  EXPECT_NEAR(t.heightAt(3.2, -2.0), 0.3 * std::sqrt(0.75), 1e-12);
  EXPECT_DOUBLE_EQ(t.heightAt(3.0, -1.75), 0.0);
  EXPECT_DOUBLE_EQ(t.heightAt(50.0, 0.0), 0.0);  // outside the extent
  EXPECT_GE(t.maxHeight(), 0.3);
}

// The height is the highest of the roughness and the shapes (a ditch's floor where a ditch is),
// whether a shape stands above the roughness's bound (its waves then go unsummed) or below it.
TEST(Terrain, HeightIsTheHighestOfRoughnessAndShapes) {
  upd::sim::Roughness rough;
  rough.rms_height_m = 0.012;  // waves of up to about 5 cm
  rough.wavelength_m = 1.0;
  rough.seed = 3;
  upd::sim::Terrain waves({-3, -3}, {3, 3});
  waves.setRoughness(rough);
  upd::sim::Box high, low;  // above and below the waves' reach
  high.center_xy = {-1.5, 0.0};
  high.height_m = 0.1;
  low.center_xy = {1.5, 0.0};
  low.height_m = 0.02;
  upd::sim::Rock rock;  // from 0.2 m at its centre down to 0 at its rim
  rock.center_xy = {0.0, 1.5};
  rock.radius_x_m = 0.5;
  rock.radius_y_m = 0.4;
  rock.height_m = 0.2;
  upd::sim::Ditch ditch;
  ditch.center_xy = {0.0, -1.5};
  ditch.length_m = 1.0;
  ditch.width_m = 0.5;
  ditch.depth_m = 0.3;
  upd::sim::Terrain t({-3, -3}, {3, 3});
  t.add(high).add(low).add(rock).add(ditch).setRoughness(rough);
  const auto inBox = [](const upd::sim::Box& b, double x, double y) {
    return std::abs(x - b.center_xy.x()) <= 0.5 * b.length_m &&
           std::abs(y - b.center_xy.y()) <= 0.5 * b.width_m;
  };
  int below_waves = 0;
  for (double y = -2.5; y <= 2.5; y += 0.0137) {
    for (double x = -2.5; x <= 2.5; x += 0.0137) {
      double expected = waves.heightAt(x, y);
      if (std::abs(x - ditch.center_xy.x()) <= 0.5 * ditch.length_m &&
          std::abs(y - ditch.center_xy.y()) <= 0.5 * ditch.width_m) {
        expected = -ditch.depth_m;
      } else {
        if (inBox(high, x, y)) expected = std::max(expected, high.height_m);
        if (inBox(low, x, y)) {
          below_waves += expected > low.height_m ? 1 : 0;
          expected = std::max(expected, low.height_m);
        }
        const double u = (x - rock.center_xy.x()) / rock.radius_x_m;
        const double v = (y - rock.center_xy.y()) / rock.radius_y_m;
        if (u * u + v * v <= 1.0) {
          expected = std::max(expected, rock.height_m * std::sqrt(1.0 - (u * u + v * v)));
        }
      }
      ASSERT_NEAR(t.heightAt(x, y), expected, 1e-12) << x << ", " << y;
    }
  }
  EXPECT_GT(below_waves, 100);  // the waves rise above the low box in places
}

TEST(Terrain, TruthRuleOnPrimitives) {
  upd::sim::Terrain t({-5, -5}, {5, 5});
  upd::sim::Box low;  // a 3 cm step: a wheel climbs it
  low.center_xy = {-3.0, 3.0};
  low.height_m = 0.03;
  upd::sim::Box wall;
  wall.center_xy = {3.0, 3.0};
  wall.length_m = 2.0;
  wall.width_m = 0.3;
  wall.height_m = 1.0;
  wall.wall = true;
  upd::sim::Ramp ramp;  // 20 deg, rising along +x from x = -1
  ramp.start_xy = {-1.0, -3.0};
  ramp.width_m = 1.0;
  ramp.height_m = 0.4;
  upd::sim::Ramp steep = ramp;
  steep.start_xy = {-1.0, 0.0};
  steep.slope_rad = 35.0 * upd::core::kDegToRad;
  t.add(low).add(wall).add(ramp).add(steep);

  EXPECT_EQ(t.truthAt(0.0, 4.5), core::Label::Traversable);
  EXPECT_EQ(t.truthAt(6.0, 0.0), core::Label::Unknown);
  EXPECT_EQ(t.truthAt(-2.5, 3.0), core::Label::Traversable);     // edge of the 3 cm step
  EXPECT_EQ(t.truthAt(3.0, 3.0), core::Label::NonTraversable);   // wall top
  EXPECT_EQ(t.truthAt(3.0, 3.19), core::Label::NonTraversable);  // wall band
  EXPECT_EQ(t.truthAt(3.0, 3.21), core::Label::Traversable);
  EXPECT_EQ(t.truthAt(-0.5, -3.0), core::Label::Traversable);   // ramp body
  EXPECT_EQ(t.truthAt(-1.0, -3.0), core::Label::Traversable);   // its foot
  EXPECT_EQ(t.truthAt(-1.04, -3.0), core::Label::Traversable);  // ground before the foot
  // The ramp's sides: lower than max_step near the foot, taller further up.
  const double tan20 = std::tan(20.0 * upd::core::kDegToRad);
  EXPECT_EQ(t.truthAt(-1.0 + 0.03 / tan20, -2.49), core::Label::Traversable);
  EXPECT_EQ(t.truthAt(-1.0 + 0.10 / tan20, -2.49), core::Label::NonTraversable);
  EXPECT_EQ(t.truthAt(-1.0 + 0.10 / tan20, -2.46), core::Label::NonTraversable);  // ground side
  EXPECT_EQ(t.truthAt(-1.0 + 0.10 / tan20, -2.44), core::Label::Traversable);
  // The top end of a ramp without a platform is a drop.
  const double top_x = -1.0 + ramp.slopeLength();
  EXPECT_EQ(t.truthAt(top_x + 0.03, -3.0), core::Label::NonTraversable);
  EXPECT_EQ(t.truthAt(top_x + 0.07, -3.0), core::Label::Traversable);
  EXPECT_EQ(t.truthAt(-0.5, 0.0), core::Label::NonTraversable);  // 35 deg body
  EXPECT_NEAR(t.slopeAt(-0.5, 0.0), 35.0 * upd::core::kDegToRad, 1e-6);
}

TEST(Terrain, SampleSurfaceLabelsFacePointsNonTraversable) {
  upd::sim::Terrain t({-1, -1}, {1, 1});
  upd::sim::Box b;
  b.center_xy = {0.0, 0.0};
  b.length_m = 1.0;
  b.width_m = 1.0;
  b.height_m = 0.2;
  t.add(b);
  const upd::sim::SurfaceSamples s = t.sampleSurface(0.02);
  ASSERT_EQ(s.surface_points, 101u * 101u);
  ASSERT_EQ(s.truth.size(), s.cloud.size());
  // Four sides of 51 columns; the corner columns are sampled once: 4 * 50 columns of 9 points.
  EXPECT_EQ(s.cloud.size() - s.surface_points, 4u * 50u * 9u);
  for (std::size_t i = s.surface_points; i < s.cloud.size(); ++i) {
    ASSERT_EQ(s.truth[i], core::Label::NonTraversable);
    ASSERT_NEAR(std::max(std::abs(s.cloud.x[i]), std::abs(s.cloud.y[i])), 0.5f, 1e-6f);
  }
  EXPECT_THROW(t.sampleSurface(0.0), std::invalid_argument);
}

TEST(Terrain, InvalidPrimitivesThrowNamingTheField) {
  upd::sim::Terrain t({0, 0}, {1, 1});
  upd::sim::Ramp r;
  r.slope_rad = 0.0;
  EXPECT_NE(thrownMessage([&] { t.add(r); }).find("Ramp.slope_rad"), std::string::npos);
  upd::sim::Box b;
  b.width_m = -1;
  EXPECT_NE(thrownMessage([&] { t.add(b); }).find("Box.width_m"), std::string::npos);
  upd::sim::Stairs st;
  st.steps = 0;
  EXPECT_NE(thrownMessage([&] { t.add(st); }).find("Stairs.steps"), std::string::npos);
  upd::sim::TruthParams tp;
  tp.border_m = -0.1;
  EXPECT_NE(thrownMessage([&] { t.setTruthParams(tp); }).find("TruthParams.border_m"),
            std::string::npos);
  EXPECT_NE(thrownMessage([] {
              upd::sim::Terrain bad({0, 0}, {0, 1});
            }).find("Terrain.max_xy"),
            std::string::npos);
}

// ------------------------------------------------------------------------------ worlds

// Traversability grid of a world: a cell is free when every truth sample within clearance_m
// is Traversable (outside the extent counts as blocked), then 8-connected search.
class Reach {
 public:
  Reach(const upd::sim::Terrain& t, double clearance_m, double cell_m = 0.05) : t_(t), cell_(cell_m) {
    nx_ = static_cast<int>((t.maxXY().x() - t.minXY().x()) / cell_m) + 1;
    ny_ = static_cast<int>((t.maxXY().y() - t.minXY().y()) / cell_m) + 1;
    std::vector<char> ok(static_cast<std::size_t>(nx_) * ny_);
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        const Eigen::Vector2d p = center(i, j);
        ok[idx(i, j)] = t.truthAt(p.x(), p.y()) == core::Label::Traversable;
      }
    }
    const int r = static_cast<int>(std::ceil(clearance_m / cell_m));
    free_.assign(ok.size(), 0);
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        bool f = true;
        for (int dj = -r; dj <= r && f; ++dj) {
          for (int di = -r; di <= r && f; ++di) {
            if ((di * di + dj * dj) * cell_m * cell_m > clearance_m * clearance_m) continue;
            const int a = i + di, b = j + dj;
            f = a >= 0 && b >= 0 && a < nx_ && b < ny_ && ok[idx(a, b)];
          }
        }
        free_[idx(i, j)] = f;
      }
    }
  }
  /// Marks every cell inside [lo, hi] blocked.
  void block(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) {
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        const Eigen::Vector2d p = center(i, j);
        if ((p.array() >= lo.array()).all() && (p.array() <= hi.array()).all())
          free_[idx(i, j)] = 0;
      }
    }
  }
  bool reachable(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const {
    const int si = cellX(from.x()), sj = cellY(from.y()), gi = cellX(to.x()), gj = cellY(to.y());
    if (!free_[idx(si, sj)] || !free_[idx(gi, gj)]) return false;
    std::vector<char> seen(free_.size(), 0);
    std::queue<std::pair<int, int>> q;
    q.push({si, sj});
    seen[idx(si, sj)] = 1;
    while (!q.empty()) {
      const auto [i, j] = q.front();
      q.pop();
      if (i == gi && j == gj) return true;
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          const int a = i + di, b = j + dj;
          if (a < 0 || b < 0 || a >= nx_ || b >= ny_) continue;
          if (!free_[idx(a, b)] || seen[idx(a, b)]) continue;
          seen[idx(a, b)] = 1;
          q.push({a, b});
        }
      }
    }
    return false;
  }
  bool lineIsFree(const Eigen::Vector2d& from, const Eigen::Vector2d& to) const {
    const int n = static_cast<int>((to - from).norm() / (0.5 * cell_)) + 1;
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector2d p = from + (to - from) * (static_cast<double>(k) / n);
      if (t_.truthAt(p.x(), p.y()) != core::Label::Traversable) return false;
    }
    return true;
  }

 private:
  std::size_t idx(int i, int j) const { return static_cast<std::size_t>(j) * nx_ + i; }
  Eigen::Vector2d center(int i, int j) const {
    return t_.minXY() + Eigen::Vector2d(i * cell_, j * cell_);
  }
  int cellX(double x) const {
    return std::clamp(static_cast<int>(std::lround((x - t_.minXY().x()) / cell_)), 0, nx_ - 1);
  }
  int cellY(double y) const {
    return std::clamp(static_cast<int>(std::lround((y - t_.minXY().y()) / cell_)), 0, ny_ - 1);
  }
  const upd::sim::Terrain& t_;
  double cell_;
  int nx_ = 0, ny_ = 0;
  std::vector<char> free_;
};

// The Dune's circumscribed radius: a planner that inflates by it must still find the way in
// every solvable world.
const double kRobotRadius_m =
    0.5 * std::hypot(upd::sim::RobotBodyParams{}.length_m, upd::sim::RobotBodyParams{}.width_m);

TEST(Worlds, NamesStartsAndGoals) {
  const std::vector<std::string> names = upd::sim::worldNames();
  for (const char* n : {"mixed", "rocks", "ramp", "ditch", "corridor", "trapped"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  }
  for (const std::string& name : names) {
    SCOPED_TRACE(name);
    const upd::sim::WorldSpec w = upd::sim::makeWorld(name);
    EXPECT_FALSE(w.description.empty());
    const upd::sim::Terrain& t = w.terrain;
    EXPECT_TRUE(t.contains(w.start_xy_yaw.x(), w.start_xy_yaw.y()));
    EXPECT_TRUE(t.contains(w.goal_xy.x(), w.goal_xy.y()));
    EXPECT_EQ(t.truthAt(w.start_xy_yaw.x(), w.start_xy_yaw.y()), core::Label::Traversable);
    EXPECT_EQ(t.truthAt(w.goal_xy.x(), w.goal_xy.y()), core::Label::Traversable);
  }
  const std::string msg = thrownMessage([] { upd::sim::makeWorld("moon"); });
  for (const std::string& name : names) EXPECT_NE(msg.find(name), std::string::npos) << msg;
}

TEST(Worlds, SolvableWorldsAreSolvableByTheRobot) {
  for (const char* name : {"mixed", "rocks", "ramp", "ditch", "corridor"}) {
    SCOPED_TRACE(name);
    const upd::sim::WorldSpec w = upd::sim::makeWorld(name);
    const Reach reach(w.terrain, kRobotRadius_m);
    EXPECT_TRUE(reach.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
  }
}

TEST(Worlds, MixedWorldHasItsFeatures) {
  const upd::sim::WorldSpec w = upd::sim::makeWorld("mixed");
  const upd::sim::Terrain& t = w.terrain;
  EXPECT_NEAR((t.maxXY() - t.minXY()).x(), 12.0, 1e-9);
  EXPECT_NEAR((t.maxXY() - t.minXY()).y(), 8.0, 1e-9);
  ASSERT_EQ(t.ramps().size(), 1u);
  EXPECT_NEAR(t.ramps()[0].slope_rad, 20.0 * upd::core::kDegToRad, 1e-12);
  EXPECT_GE(t.rocks().size(), 3u);
  bool step = false, platform = false;
  for (const upd::sim::Box& b : t.boxes()) {
    step |= std::abs(b.height_m - 0.15) < 1e-9;
    platform |= std::abs(b.height_m - 0.3) < 1e-9;
  }
  EXPECT_TRUE(step);
  EXPECT_TRUE(platform);
  ASSERT_EQ(t.ditches().size(), 1u);
  EXPECT_NEAR(t.ditches()[0].width_m, 0.6, 1e-12);
  const upd::sim::Ditch& d = t.ditches()[0];
  EXPECT_EQ(t.truthAt(d.center_xy.x(), d.center_xy.y()), core::Label::NonTraversable);
  EXPECT_NEAR(t.heightAt(d.center_xy.x(), d.center_xy.y()), -d.depth_m, 1e-12);
  // Climbing the ramp reaches the platform top.
  const upd::sim::Ramp& r = t.ramps()[0];
  const Eigen::Vector2d dir(std::cos(r.yaw_rad), std::sin(r.yaw_rad));
  const Eigen::Vector2d mid = r.start_xy + 0.5 * r.slopeLength() * dir;
  const Eigen::Vector2d top = r.start_xy + (r.slopeLength() + 0.5) * dir;
  EXPECT_NEAR(t.heightAt(mid.x(), mid.y()), 0.15, 1e-9);
  EXPECT_NEAR(t.heightAt(top.x(), top.y()), 0.3, 1e-9);
  EXPECT_EQ(t.truthAt(mid.x(), mid.y()), core::Label::Traversable);
  EXPECT_EQ(t.truthAt(top.x(), top.y()), core::Label::Traversable);
  for (const upd::sim::Rock& rock : t.rocks()) {
    const core::Label l = t.truthAt(rock.center_xy.x(), rock.center_xy.y());
    EXPECT_EQ(l, rock.height_m > 0.05 ? core::Label::NonTraversable : core::Label::Traversable);
  }
}

TEST(Worlds, RampWorldPlatformIsReachedOnlyByTheRamp) {
  const upd::sim::WorldSpec w = upd::sim::makeWorld("ramp");
  const upd::sim::Terrain& t = w.terrain;
  EXPECT_NEAR(t.heightAt(w.goal_xy.x(), w.goal_xy.y()), 0.3, 1e-9);  // goal on the platform
  ASSERT_EQ(t.ramps().size(), 1u);
  const upd::sim::Ramp& r = t.ramps()[0];
  EXPECT_NEAR(r.slope_rad, 20.0 * upd::core::kDegToRad, 1e-12);
  ASSERT_NEAR(r.yaw_rad, 90.0 * upd::core::kDegToRad, 1e-12);  // climbs +y: the block below uses it
  Reach reach(t, kRobotRadius_m);
  ASSERT_TRUE(reach.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
  EXPECT_FALSE(reach.lineIsFree(w.start_xy_yaw.head<2>(), w.goal_xy));
  // Without the ramp (its footprint blocked) even a point robot cannot get up.
  Reach point(t, 0.0);
  ASSERT_TRUE(point.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
  const Eigen::Vector2d a = r.start_xy + Eigen::Vector2d(-0.5 * r.width_m, 0.2);
  const Eigen::Vector2d b = r.start_xy + Eigen::Vector2d(0.5 * r.width_m, 0.6);
  point.block(a, b);
  EXPECT_FALSE(point.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
}

TEST(Worlds, ObstacleWorldsBlockTheStraightLine) {
  for (const char* name : {"rocks", "ditch", "corridor", "trapped"}) {
    SCOPED_TRACE(name);
    const upd::sim::WorldSpec w = upd::sim::makeWorld(name);
    const Reach reach(w.terrain, 0.0);
    if (std::string(name) == "corridor") {
      // The chicane: two steps each blocking half of the corridor.
      EXPECT_FALSE(reach.lineIsFree({1.0, 0.8}, {11.0, 0.8}));
      EXPECT_FALSE(reach.lineIsFree({1.0, -0.8}, {11.0, -0.8}));
    } else {
      EXPECT_FALSE(reach.lineIsFree(w.start_xy_yaw.head<2>(), w.goal_xy));
    }
  }
}

TEST(Worlds, DitchAndCorridorHaveOneWayThrough) {
  {
    const upd::sim::WorldSpec w = upd::sim::makeWorld("ditch");
    Reach reach(w.terrain, 0.0);
    ASSERT_TRUE(reach.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
    reach.block({4.0, 2.0}, {6.0, 4.0});  // the way round the ditch's end
    EXPECT_FALSE(reach.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
  }
  {
    const upd::sim::WorldSpec w = upd::sim::makeWorld("corridor");
    Reach reach(w.terrain, 0.0);
    ASSERT_TRUE(reach.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
    reach.block({5.9, -1.6}, {6.1, 1.6});  // across the corridor
    EXPECT_FALSE(reach.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
  }
}

TEST(Worlds, TrappedGoalIsUnreachable) {
  const upd::sim::WorldSpec w = upd::sim::makeWorld("trapped");
  const Reach reach(w.terrain, 0.0);
  EXPECT_FALSE(reach.reachable(w.start_xy_yaw.head<2>(), w.goal_xy));
  EXPECT_GT(w.terrain.heightAt(w.goal_xy.x() + 1.125, w.goal_xy.y()), 0.5);  // a wall
}

}  // namespace
