// The simulated depth camera and the terrain ray caster: analytic depths, vertical faces,
// the Kinect noise model, invalid pixels and the labelled organized cloud.
#include "upd/sim/render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace core = upd::core;

namespace {

using upd::core::Label;

upd::sim::DepthNoise noiseFree() {
  upd::sim::DepthNoise n;
  n.sigma_coeff_per_m = 0.0;
  n.quantize_mm = false;
  return n;
}

upd::sim::Terrain flatWorld() { return upd::sim::Terrain({-50, -50}, {50, 50}); }

// A wall whose face is the plane x = distance_m, 10 m wide and 5 m high.
upd::sim::Terrain wallWorld(double distance_m) {
  upd::sim::Terrain t({-20, -20}, {20, 20});
  upd::sim::Box wall;
  wall.center_xy = {distance_m + 0.25, 0.0};
  wall.length_m = 0.5;
  wall.width_m = 10.0;
  wall.height_m = 5.0;
  wall.wall = true;
  t.add(wall);
  return t;
}

Eigen::Vector3d pixelRay(const upd::core::CameraIntrinsics& K, int u, int v) {
  return {(u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0};
}

TEST(CameraPose, LooksAtTheTargetWithRowsDown) {
  const Eigen::Vector3d eye(1, 2, 1.5), target(4, 0, 0);
  const Eigen::Isometry3d pose = upd::sim::cameraPoseLookingAt(eye, target);
  EXPECT_TRUE(pose.translation().isApprox(eye));
  EXPECT_TRUE(pose.linear().col(2).isApprox((target - eye).normalized()));
  EXPECT_NEAR(pose.linear().col(0).z(), 0.0, 1e-12);  // image rows are level
  EXPECT_LT(pose.linear().col(1).z(), 0.0);           // image y points down
  EXPECT_NEAR(pose.linear().determinant(), 1.0, 1e-12);
  EXPECT_TRUE((pose.linear().transpose() * pose.linear()).isIdentity(1e-12));
  EXPECT_THROW(upd::sim::cameraPoseLookingAt(eye, eye), std::invalid_argument);
  EXPECT_THROW(upd::sim::cameraPoseLookingAt(eye, eye - Eigen::Vector3d::UnitZ()),
               std::invalid_argument);
}

TEST(RenderDepth, FlatGroundMatchesTheRayPlaneIntersection) {
  const upd::core::CameraIntrinsics K;
  const Eigen::Isometry3d pose = upd::sim::cameraPoseLookingAt({0, 0, 1.0}, {3, 0.5, 0});
  const upd::sim::DepthNoise noise = noiseFree();
  const upd::core::DepthImage img = upd::sim::renderDepth(flatWorld(), pose, K, noise, 1);
  ASSERT_EQ(img.width, K.width);
  ASSERT_EQ(img.height, K.height);
  std::size_t valid = 0, sky = 0;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const Eigen::Vector3d ray_w = pose.linear() * pixelRay(K, u, v);
      // Ray eye + s ray_w meets z = 0 at s = -eye_z / ray_w_z; ray_c has z = 1, so z-depth = s.
      const double s = ray_w.z() < 0 ? -pose.translation().z() / ray_w.z() : -1.0;
      const bool in_range = s >= noise.min_range_m && s <= noise.max_range_m;
      if (in_range) {
        ASSERT_NEAR(img.at(u, v), s, 1e-5 * s) << u << "," << v;
        ++valid;
      } else {
        ASSERT_EQ(img.at(u, v), 0.f) << u << "," << v << " s = " << s;
        sky += ray_w.z() >= 0 ? 1 : 0;
      }
    }
  }
  EXPECT_GT(valid, static_cast<std::size_t>(K.width) * K.height / 3);
  EXPECT_GT(sky, 1000u);  // the camera looks down at 18 deg: the top rows see the sky
}

TEST(RenderDepth, SkyPixelsAreInvalid) {
  const upd::core::CameraIntrinsics K;
  const Eigen::Isometry3d pose = upd::sim::cameraPoseLookingAt({0, 0, 1.0}, {3, 0, 3.0});
  const upd::core::DepthImage img = upd::sim::renderDepth(flatWorld(), pose, K, upd::sim::DepthNoise{}, 1);
  for (float d : img.depth_m) ASSERT_EQ(d, 0.f);
}

TEST(RenderDepth, VerticalWallAppearsAtItsDistance) {
  const upd::core::CameraIntrinsics K;
  const Eigen::Isometry3d pose = upd::sim::cameraPoseLookingAt({0, 0, 1.0}, {1, 0, 1.0});
  const upd::core::DepthImage img = upd::sim::renderDepth(wallWorld(3.0), pose, K, noiseFree(), 1);
  // Looking straight at a wall perpendicular to the optical axis every pixel has z = 3 (the
  // bottom rows reach z = 0 at 1 / 0.456 = 2.19 m: they see the ground first).
  std::size_t on_wall = 0;
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const double ground_s = (v - K.cy) > 0 ? 1.0 / ((v - K.cy) / K.fy) : 1e9;
      if (ground_s < 3.0) {
        ASSERT_NEAR(img.at(u, v), ground_s, 1e-5 * ground_s);
      } else {
        ASSERT_NEAR(img.at(u, v), 3.0, 1e-5) << u << "," << v;
        ++on_wall;
      }
    }
  }
  EXPECT_GT(on_wall, static_cast<std::size_t>(K.width) * K.height / 2);
}

TEST(RenderDepth, NoiseSigmaGrowsWithTheSquareOfDepth) {
  const upd::core::CameraIntrinsics K;
  const Eigen::Isometry3d pose = upd::sim::cameraPoseLookingAt({0, 0, 2.5}, {1, 0, 2.5});
  for (double z : {2.0, 4.0}) {
    SCOPED_TRACE(z);
    upd::sim::DepthNoise noise;  // Kinect defaults: 1.2e-3 z^2, millimetre steps
    const upd::core::DepthImage img = upd::sim::renderDepth(wallWorld(z), pose, K, noise, 7);
    double sum = 0, sum2 = 0;
    std::size_t n = 0;
    for (float d : img.depth_m) {
      ASSERT_GT(d, 0.f);
      const double mm = d * 1000.0;
      ASSERT_NEAR(mm, std::round(mm), 1e-3);  // quantized to the millimetre
      sum += d - z;
      sum2 += (d - z) * (d - z);
      ++n;
    }
    const double mean = sum / n, sigma = std::sqrt(sum2 / n - mean * mean);
    const double expected = noise.sigma_coeff_per_m * z * z;
    EXPECT_NEAR(mean, 0.0, 0.01 * expected);
    // Rounding adds 1 mm^2 / 12 of variance.
    EXPECT_NEAR(sigma, std::sqrt(expected * expected + 1e-6 / 12), 0.02 * expected);
  }
}

TEST(RenderDepth, SameSeedSameImageOtherSeedOther) {
  const upd::core::CameraIntrinsics K;
  const Eigen::Isometry3d pose = upd::sim::cameraPoseLookingAt({0, 0, 1.0}, {3, 0, 0});
  const upd::sim::WorldSpec w = upd::sim::makeWorld("mixed");
  const upd::core::DepthImage a = upd::sim::renderDepth(w.terrain, pose, K, upd::sim::DepthNoise{}, 3);
  const upd::core::DepthImage b = upd::sim::renderDepth(w.terrain, pose, K, upd::sim::DepthNoise{}, 3);
  const upd::core::DepthImage c = upd::sim::renderDepth(w.terrain, pose, K, upd::sim::DepthNoise{}, 4);
  EXPECT_EQ(a.depth_m, b.depth_m);
  std::size_t differ = 0;
  for (std::size_t i = 0; i < a.depth_m.size(); ++i) differ += a.depth_m[i] != c.depth_m[i];
  EXPECT_GT(differ, a.depth_m.size() / 4);
}

TEST(RenderDepth, RangeLimitsInvalidateDepth) {
  const upd::core::CameraIntrinsics K;
  const Eigen::Isometry3d pose = upd::sim::cameraPoseLookingAt({0, 0, 2.5}, {1, 0, 2.5});
  // Nearer than min_range_m: the wall fills the image.
  const upd::core::DepthImage near = upd::sim::renderDepth(wallWorld(0.3), pose, K, noiseFree(), 1);
  for (float d : near.depth_m) ASSERT_EQ(d, 0.f);
  // Beyond max_range_m: the upper half sees only the wall (the lower half sees the ground
  // within 5.5 m).
  const upd::core::DepthImage far = upd::sim::renderDepth(wallWorld(9.0), pose, K, noiseFree(), 1);
  for (int v = 0; v < K.height; ++v) {
    for (int u = 0; u < K.width; ++u) {
      const double ground_s = (v - K.cy) > 0 ? 2.5 / ((v - K.cy) / K.fy) : 1e9;
      ASSERT_EQ(far.at(u, v), ground_s <= 8.0 ? far.at(u, v) : 0.f) << u << "," << v;
      if (ground_s <= 7.9) {
        ASSERT_GT(far.at(u, v), 0.f);
      }
    }
  }
}

TEST(RenderDepth, BadParametersThrowNamingTheField) {
  upd::sim::DepthNoise n;
  n.max_range_m = 0.1;  // below min_range_m
  try {
    upd::sim::renderDepth(flatWorld(), Eigen::Isometry3d::Identity(), upd::core::CameraIntrinsics{}, n, 1);
    FAIL() << "nothing thrown";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("DepthNoise.max_range_m"), std::string::npos) << e.what();
  }
  n = {};
  n.sigma_coeff_per_m = -1;
  EXPECT_THROW(n.validate(), std::invalid_argument);
}

// Hit point on the surface: at the height there, or on a vertical face (between the heights
// just either side of it).
bool onSurface(const upd::sim::Terrain& t, const Eigen::Vector3d& p, double tol_m) {
  if (std::abs(p.z() - t.heightAt(p.x(), p.y())) < tol_m) return true;
  const double e = 10 * tol_m;
  double lo = 1e9, hi = -1e9;
  for (const Eigen::Vector2d& d : {Eigen::Vector2d(e, 0), Eigen::Vector2d(-e, 0),
                                   Eigen::Vector2d(0, e), Eigen::Vector2d(0, -e)}) {
    const double h = t.heightAt(p.x() + d.x(), p.y() + d.y());
    lo = std::min(lo, h);
    hi = std::max(hi, h);
  }
  return p.z() > lo - tol_m && p.z() < hi + tol_m;
}

TEST(RenderScene, OrganizedCloudLandsOnTheTerrainWithTruth) {
  const upd::sim::WorldSpec w = upd::sim::makeWorld("mixed");
  const upd::core::CameraIntrinsics K;
  // Looking from the start along the ramp, platform, ditch and step side of the world.
  const Eigen::Isometry3d pose = upd::sim::cameraPoseLookingAt({1.5, 0.0, 1.2}, {6.0, -2.0, 0.0});
  const upd::sim::RenderedScene r = upd::sim::renderScene(w.terrain, pose, K, noiseFree(), 1, "mixed");
  const upd::core::PointCloud& c = r.scene.cloud;
  ASSERT_TRUE(c.isOrganized());
  ASSERT_EQ(c.width, static_cast<std::size_t>(K.width));
  ASSERT_EQ(c.height, static_cast<std::size_t>(K.height));
  ASSERT_EQ(r.scene.truth.size(), c.size());
  EXPECT_EQ(r.scene.name, "mixed");
  EXPECT_TRUE(c.sensor_origin.isZero());
  EXPECT_TRUE(r.scene.up.isApprox(
      (pose.linear().transpose() * Eigen::Vector3d::UnitZ()).cast<float>(), 1e-6f));
  std::size_t valid = 0, faces = 0, trav = 0, non_trav = 0, agree = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!c.isFinite(i)) {
      ASSERT_EQ(r.scene.truth[i], core::Label::Unknown);
      ASSERT_EQ(r.depth.depth_m[i], 0.f);
      continue;
    }
    ++valid;
    const Eigen::Vector3d p = pose * c.point(i).cast<double>();
    // Float coordinates at up to 8 m: a few micrometres.
    ASSERT_TRUE(onSurface(w.terrain, p, 1e-4)) << p.transpose();
    faces += std::abs(p.z() - w.terrain.heightAt(p.x(), p.y())) > 1e-4 ? 1 : 0;
    trav += r.scene.truth[i] == core::Label::Traversable;
    non_trav += r.scene.truth[i] == core::Label::NonTraversable;
    agree += r.scene.truth[i] == w.terrain.truthAt(p.x(), p.y());
  }
  EXPECT_GT(valid, c.size() / 2);
  EXPECT_GT(faces, 100u);  // the platform's front, the step and the ditch walls
  EXPECT_GT(trav, valid / 2);
  EXPECT_GT(non_trav, 1000u);
  // The labels are of the exact hits; the float cloud moves a few points across a band edge.
  EXPECT_GT(agree, valid - valid / 1000);
}

TEST(Raycast, HitsVerticalFacesAndFloors) {
  upd::sim::Terrain t({-5, -5}, {5, 5});
  upd::sim::Box step;
  step.center_xy = {1.5, 0.0};
  step.length_m = 1.0;  // face at x = 1
  step.width_m = 2.0;
  step.height_m = 0.15;
  upd::sim::Ditch ditch;
  ditch.center_xy = {-2.0, 0.0};
  ditch.length_m = 0.6;  // walls at x = -2.3 and -1.7
  ditch.width_m = 2.0;
  ditch.depth_m = 0.3;
  t.add(step).add(ditch);

  auto hit = t.raycast({0, 0, 0.05}, {1, 0, 0}, 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->x(), 1.0, 1e-6);
  EXPECT_NEAR(hit->z(), 0.05, 1e-12);

  // Down into the ditch from above its near rim: steeply onto the floor, shallowly onto the
  // far wall.
  hit = t.raycast({-1.7, 0, 0.1}, {-1, 0, -1}, 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->x(), -2.1, 1e-6);
  EXPECT_NEAR(hit->z(), -0.3, 1e-6);
  hit = t.raycast({-1.7, 0, 0.1}, {-1, 0, -0.5}, 10.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->x(), -2.3, 1e-6);
  EXPECT_NEAR(hit->z(), -0.2, 1e-6);

  // Beyond the extent the world is the plane z = 0.
  hit = t.raycast({4.0, 4.0, 1.0}, {1, 1, -0.2}, 20.0);
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->z(), 0.0, 1e-12);
  EXPECT_NEAR(hit->x(), 4.0 + 1.0 / 0.2, 1e-9);

  EXPECT_FALSE(t.raycast({0, 0, 1}, {0, 0, 1}, 10.0));      // up into the sky
  EXPECT_FALSE(t.raycast({0, 0, 1}, {0, 0, -1}, 0.5));      // out of range
  EXPECT_FALSE(t.raycast({1.5, 0, 0.1}, {1, 0, 0}, 10.0));  // starts inside the step
  EXPECT_THROW(t.raycast({0, 0, 1}, {0, 0, 0}, 1.0), std::invalid_argument);
}

// The fast ray caster (cell skipping, 1 cm march, bisection) against a plain 1 mm march.
TEST(Raycast, AgreesWithABruteForceMarch) {
  const upd::sim::WorldSpec w = upd::sim::makeWorld("mixed");
  const upd::sim::Terrain& t = w.terrain;
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(0.5, 11.5), uy(-3.5, 3.5), uz(0.4, 2.0),
      angle(-3.14159, 3.14159), down(0.1, 1.2);
  int hits = 0;
  for (int k = 0; k < 300; ++k) {
    const Eigen::Vector3d o(ux(rng), uy(rng), uz(rng));
    const double a = angle(rng), e = down(rng);
    const Eigen::Vector3d d(std::cos(a) * std::cos(e), std::sin(a) * std::cos(e), -std::sin(e));
    double brute = -1;
    for (double s = 0; s <= 10.0; s += 1e-3) {
      const Eigen::Vector3d p = o + s * d;
      if (p.z() <= t.heightAt(p.x(), p.y())) {
        brute = s;
        break;
      }
    }
    const auto hit = t.raycast(o, d, 10.0);
    ASSERT_EQ(hit.has_value(), brute >= 0) << k;
    if (!hit) continue;
    ++hits;
    EXPECT_NEAR((*hit - o).norm(), brute, 1.5e-3) << k << " origin " << o.transpose();
  }
  EXPECT_GT(hits, 250);
}

}  // namespace
