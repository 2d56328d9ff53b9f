// The fast paths (fast_normals.h, fast_upd.h) against the exact path: the same neighbourhoods
// for normals, and the UPD within the agreement promised by docs/PERFORMANCE.md (mean
// |delta zeta| <= 0.005, the same label on >= 99.5 % of the points) on generated scenes and a
// simulated Kinect frame; the properties the fast path keeps exactly (planes, translation far
// from the origin); degenerate inputs. The benchmark (bench/upd_bench) repeats the agreement on
// the real frames and times everything; no timing is asserted here.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "exact_agreement.h"
#include "synthetic.h"
#include "upd/core/classify.h"
#include "upd/core/fast_normals.h"
#include "upd/core/fast_upd.h"
#include "upd/core/kdtree.h"
#include "upd/core/pipeline.h"
#include "upd/sim/render.h"
#include "upd/sim/scenes.h"
#include "upd/sim/terrain.h"

namespace upd::core {
namespace {

using namespace upd::sim;  // generated scenes as test inputs

using test::Agreement;
using test::agreeWithExact;

// Angle between two unit normals [rad] (their orientation is compared separately).
double angleBetween(const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
  return std::acos(std::clamp(static_cast<double>(a.dot(b)), -1.0, 1.0));
}

// A simulated Kinect frame of the "mixed" world (a ramp, rocks, a step, a ditch), at a quarter
// of the Kinect's resolution so the exact reference stays quick.
RenderedScene kinectFrame() {
  CameraIntrinsics K;
  K.width = 320, K.height = 240, K.fx = K.fy = 262.5, K.cx = 159.5, K.cy = 119.5;
  DepthNoise noise;
  noise.max_range_m = 5.0;
  return renderScene(makeWorld("mixed").terrain,
                     cameraPoseLookingAt({1.0, 0.3, 0.6}, {4.5, -0.4, 0.0}), K, noise, 7);
}

TEST(FastNormals, GridEqualsTheExactPath) {
  for (const NormalWeighting weighting : {NormalWeighting::Uniform, NormalWeighting::Gaussian}) {
    PointCloud c = test::makeRandomCloud(3000, 5, 1.f);
    c.sensor_origin = Eigen::Vector3f(0, 0, 3);
    NormalParams p;
    p.radius_m = 0.12;
    p.weighting = weighting;
    const KdTree tree(c);
    const Normals exact = computeNormals(c, tree, p, Eigen::Vector3f::UnitZ());
    const Normals grid = computeNormalsGrid(c, p, Eigen::Vector3f::UnitZ());
    EXPECT_EQ(grid.invalid, exact.invalid);
    for (std::size_t i = 0; i < c.size(); ++i) {
      ASSERT_EQ(grid.isValid(i), exact.isValid(i)) << "point " << i;
      if (!exact.isValid(i)) continue;
      EXPECT_NEAR((grid.normal(i) - exact.normal(i)).norm(), 0.f, 1e-4f) << "point " << i;
      EXPECT_NEAR(grid.curvature[i], exact.curvature[i], 1e-4f) << "point " << i;
    }
  }
}

// The grid normals find a point's 27 cells by a dense table over the cells' box, or by a hash
// where that box is mostly empty: a far lone point switches to the hash and changes no other
// point's normal, bit for bit (the same cells, candidates and sums).
TEST(FastNormals, GridCellTableAndHashGiveTheSameNormals) {
  for (const NormalWeighting weighting : {NormalWeighting::Uniform, NormalWeighting::Gaussian}) {
    PointCloud c = test::makeRandomCloud(3000, 11, 1.f);
    c.x[17] = std::numeric_limits<float>::quiet_NaN();
    c.sensor_origin = Eigen::Vector3f(0, 0, 3);
    NormalParams p;
    p.radius_m = 0.12;
    p.weighting = weighting;
    const Normals dense = computeNormalsGrid(c, p, Eigen::Vector3f::UnitZ());
    PointCloud far = c;
    far.push_back(900.f, -700.f, 800.f);
    const Normals hashed = computeNormalsGrid(far, p, Eigen::Vector3f::UnitZ());
    EXPECT_EQ(hashed.invalid, dense.invalid + 1);
    EXPECT_FALSE(hashed.isValid(c.size()));
    EXPECT_GT(c.size() - dense.invalid, 2500u);
    for (std::size_t i = 0; i < c.size(); ++i) {
      ASSERT_EQ(hashed.isValid(i), dense.isValid(i)) << "point " << i;
      if (!dense.isValid(i)) continue;
      ASSERT_EQ(hashed.normal(i), dense.normal(i)) << "point " << i;
      ASSERT_EQ(hashed.curvature[i], dense.curvature[i]) << "point " << i;
    }
  }
}

TEST(FastNormals, OrganizedScansFindTheExactNeighbourhoods) {
  const RenderedScene rs = kinectFrame();
  const PointCloud& c = rs.scene.cloud;
  NormalParams p;
  p.radius_m = 0.05;
  p.fast_block_px = 1;  // a normal per pixel: the scans alone
  p.fast_scan_px = 24;  // wider than the ball beyond ~1.3 m in this quarter-resolution frame
  const KdTree tree(c);
  const Normals exact = computeNormals(c, tree, p, rs.scene.up);
  const Normals fast = computeNormalsOrganized(c, p, rs.scene.up);
  // Beyond 2 m the ball spans fewer than 24 pixels and its window is scanned whole: the same
  // points as the k-d tree (in float instead of double). Nearer, every 2nd row and column.
  std::vector<double> far_angles, near_angles;
  std::size_t flipped = 0, validity_differs = 0;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (exact.isValid(i) != fast.isValid(i)) ++validity_differs;
    if (!exact.isValid(i) || !fast.isValid(i)) continue;
    const double angle = angleBetween(exact.normal(i), fast.normal(i));
    (c.point(i).norm() > 2.f ? far_angles : near_angles).push_back(angle);
    flipped += exact.normal(i).dot(fast.normal(i)) < 0.f ? 1 : 0;
  }
  ASSERT_GT(far_angles.size(), c.size() / 10);
  ASSERT_GT(near_angles.size(), c.size() / 10);
  std::sort(far_angles.begin(), far_angles.end());
  std::sort(near_angles.begin(), near_angles.end());
  // The last few per cent are neighbourhoods of a few points without a clear plane (curvature
  // > 0.1, l0 ~ l1), whose smallest eigenvector is ill-defined in either path.
  EXPECT_LT(far_angles[far_angles.size() * 97 / 100], 1e-3);
  EXPECT_LT(near_angles[near_angles.size() / 2], 2e-2);
  EXPECT_LE(flipped, (far_angles.size() + near_angles.size()) / 1000);
  EXPECT_LE(validity_differs, c.size() / 1000);
}

// The organized normals' invalid count is the number of pixels left without a normal, a pixel
// without a point gets none, and the others do unless their window found no plane; on image
// widths that are and are not a multiple of the vector width, with NaN holes and a NaN row.
TEST(FastNormals, OrganizedInvalidCountIsThePixelsWithoutANormal) {
  const PointCloud full = kinectFrame().scene.cloud;
  for (const std::size_t width : {full.width, full.width - 3}) {
    PointCloud c;
    c.resizeOrganized(width, full.height);
    c.sensor_origin = full.sensor_origin;
    std::size_t holes = 0;
    for (std::size_t v = 0; v < c.height; ++v) {
      for (std::size_t u = 0; u < width; ++u) {
        const std::size_t i = v * width + u, j = v * full.width + u;
        if ((u * 7 + v * 13) % 29 == 0 || v == 40) continue;  // (NaN: resizeOrganized's fill)
        c.x[i] = full.x[j], c.y[i] = full.y[j], c.z[i] = full.z[j];
      }
    }
    for (std::size_t i = 0; i < c.size(); ++i) holes += c.isFinite(i) ? 0 : 1;
    NormalParams p;
    p.radius_m = 0.05;
    Normals n;
    computeNormalsOrganized(c, p, Eigen::Vector3f::UnitZ(), n);
    ASSERT_EQ(n.size(), c.size());
    std::size_t without = 0, finite_without = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
      if (!c.isFinite(i)) {
        ASSERT_FALSE(n.isValid(i)) << "pixel " << i;
        ASSERT_TRUE(std::isnan(n.curvature[i])) << "pixel " << i;
      }
      without += n.isValid(i) ? 0 : 1;
      finite_without += c.isFinite(i) && !n.isValid(i) ? 1 : 0;
    }
    EXPECT_EQ(n.invalid, without) << "width " << width;
    EXPECT_GT(holes, c.size() / 20);
    EXPECT_LT(finite_without, (c.size() - holes) / 50) << "width " << width;
  }
}

// A generated scene on a 0.02 m grid with 2 mm of noise, and its exact normals (r = 0.05 m).
Scene noisyScene(const std::string& name) {
  SceneParams sp;
  sp.spacing_m = 0.02;
  sp.noise_m = 0.002;
  return makeScene(name, sp);
}
Normals exactNormals(const Scene& s) {
  NormalParams np;
  np.radius_m = 0.05;
  return computeNormals(s.cloud, KdTree(s.cloud), np, s.up);
}

TEST(FastUpd, AgreesWithTheExactPathOnGeneratedScenes) {
  for (const std::string name : {"corner", "ramp", "step", "stairs", "ditch", "rocks"}) {
    SCOPED_TRACE(name);
    const Scene s = noisyScene(name);
    const Normals normals = exactNormals(s);
    UpdParams defaults;
    defaults.radius_m = 0.5;
    const Agreement d = agreeWithExact(s.cloud, normals, computeUpdFast(s.cloud, normals, defaults),
                                       defaults, s.up, 3);
    EXPECT_LE(d.mean_abs_dzeta, 0.007);
    EXPECT_GE(d.sameLabelFraction(), 0.98);
    EXPECT_LE(d.validity_differs, d.compared / 200);
    UpdParams accurate = defaults;
    accurate.fast_cells_per_radius = 8;
    accurate.fast_refine_spread = 0.02;
    const Agreement a = agreeWithExact(s.cloud, normals, computeUpdFast(s.cloud, normals, accurate),
                                       accurate, s.up, 3);
    EXPECT_LE(a.mean_abs_dzeta, 0.005);
    EXPECT_GE(a.sameLabelFraction(), 0.995);
    EXPECT_LE(a.validity_differs, a.compared / 200);
  }
}

// Brute-force eq. 6 at point i over the finite points within d_m (distances in double), and
// how many points lie so close to the sphere (1e-6 d_m) that float rounding may put them on
// either side: the exact sums are equal up to those.
struct BruteSums {
  Eigen::Vector3d r = Eigen::Vector3d::Zero();
  std::uint32_t k = 0, ambiguous = 0;
};
BruteSums bruteSums(const PointCloud& c, const Normals& n, std::size_t i, double d_m) {
  BruteSums b;
  for (std::size_t j = 0; j < c.size(); ++j) {
    if (!c.isFinite(j) || !n.isValid(j)) continue;
    const double d = (c.point(j).cast<double>() - c.point(i).cast<double>()).norm();
    if (std::abs(d - d_m) < 1e-6 * d_m) ++b.ambiguous;
    if (d > d_m) continue;
    b.r += n.normal(j).cast<double>();
    ++b.k;
  }
  return b;
}

// fast_exact_band: the points whose interpolated zeta lies within the band of the label
// threshold get the exact path's sums (the same normals in, the same r and k out), every other
// point keeps its interpolated values, and the labels then agree on >= 99.5 % of the points.
TEST(FastUpd, PointsNearTheLabelThresholdGetTheExactSums) {
  for (const std::string name : {"corner", "step", "rocks"}) {
    SCOPED_TRACE(name);
    const Scene s = noisyScene(name);
    const Normals normals = exactNormals(s);
    UpdParams p;
    p.radius_m = 0.5;
    const UpdResult interpolated = computeUpdFast(s.cloud, normals, p);
    const double threshold = ClassifyParams{}.zeta_min;
    p.fast_exact_band = 0.02;
    FastUpdStats st;
    const UpdResult banded = computeUpdFast(s.cloud, normals, p, &st, threshold);
    std::size_t in_band = 0;
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
      const float z = interpolated.zeta[i];
      if (!(std::abs(z - threshold) < p.fast_exact_band)) {
        // Outside the band (or unscored): the interpolated values, bit for bit.
        ASSERT_EQ(banded.isValid(i), interpolated.isValid(i)) << "point " << i;
        if (!banded.isValid(i)) continue;
        ASSERT_EQ(banded.zeta[i], interpolated.zeta[i]) << "point " << i;
        ASSERT_EQ(banded.rx[i], interpolated.rx[i]) << "point " << i;
        continue;
      }
      ++in_band;
      ASSERT_TRUE(banded.isValid(i)) << "point " << i;
      const BruteSums b = bruteSums(s.cloud, normals, i, p.radius_m);
      EXPECT_LE(std::abs(static_cast<double>(banded.k[i]) - b.k), b.ambiguous) << "point " << i;
      EXPECT_LE((banded.r(i).cast<double>() - b.r).norm(), 1e-5 * b.k + b.ambiguous)
          << "point " << i;
      EXPECT_NEAR(banded.zeta[i], b.r.norm() / b.k, 2e-5 + 2.0 * b.ambiguous / b.k)
          << "point " << i;
    }
    EXPECT_GT(in_band, 50u);
    EXPECT_EQ(st.exact_points, in_band);
    EXPECT_EQ(banded.invalid, interpolated.invalid);
    const Agreement a = agreeWithExact(s.cloud, normals, banded, p, s.up, 3);
    EXPECT_GE(a.sameLabelFraction(), 0.995);
    // Without a threshold there is no band.
    const UpdResult no_threshold = computeUpdFast(s.cloud, normals, p);
    EXPECT_EQ(no_threshold.zeta, interpolated.zeta);
  }
}

// The pipeline passes the classifier's zeta_min as the threshold of the band.
TEST(FastPipeline, ExactBandFollowsTheClassifierThreshold) {
  SceneParams sp;
  sp.spacing_m = 0.02;
  const Scene s = makeScene("step", sp);
  PipelineParams p;
  p.up = s.up;
  p.preprocess.disableAll();
  p.upd.method = UpdMethod::Fast;
  p.upd.fast_exact_band = 0.02;
  for (const double zeta_min : {0.9, 0.95}) {
    p.classify.zeta_min = zeta_min;
    p.classify.zeta_caution = std::max(zeta_min, p.classify.zeta_caution);
    const PipelineResult r = runPipeline(s.cloud, p);
    PipelineParams off = p;
    off.upd.fast_exact_band = 0;
    const PipelineResult o = runPipeline(s.cloud, off);
    std::size_t in_band = 0;
    for (std::size_t i = 0; i < r.cloud.size(); i += 3) {
      if (!(std::abs(o.upd.zeta[i] - zeta_min) < 0.02)) continue;
      ++in_band;
      const BruteSums b = bruteSums(r.cloud, r.normals, i, p.upd.radius_m);
      EXPECT_NEAR(r.upd.zeta[i], b.r.norm() / b.k, 2e-5 + 2.0 * b.ambiguous / b.k) << "point " << i;
    }
    EXPECT_GT(in_band, 20u) << "zeta_min " << zeta_min;
  }
}

TEST(FastPipeline, KinectFrameAgreesWithTheExactPath) {
  const RenderedScene rs = kinectFrame();
  PipelineParams p;
  p.up = rs.scene.up;
  p.preprocess.disableAll();  // keep the image: every pixel is scored
  p.normals.radius_m = 0.05;
  p.upd.radius_m = 0.5;
  p.upd.method = UpdMethod::Fast;
  const PipelineResult fast = runPipeline(rs.scene.cloud, p);
  ASSERT_EQ(fast.method, UpdMethod::Fast);
  ASSERT_TRUE(fast.organized_normals);
  ASSERT_EQ(fast.cloud.size(), rs.scene.cloud.size());
  const KdTree tree(fast.cloud);
  const Normals exact_normals = computeNormals(fast.cloud, tree, p.normals, p.unitUp());
  const Agreement a = agreeWithExact(fast.cloud, exact_normals, fast.upd, p.upd, p.unitUp(), 7);
  ASSERT_GT(a.compared, 5000u);
  EXPECT_LE(a.mean_abs_dzeta, 0.005);
  EXPECT_GE(a.sameLabelFraction(), 0.995);
}

TEST(FastUpd, PlaneOfAnyTiltHasZetaOneAndTheTiltAsSlope) {
  for (const double tilt_deg : {0.0, 20.0, 60.0}) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.linear() = (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
                     Eigen::AngleAxisd(tilt_deg * kDegToRad, Eigen::Vector3d::UnitX()))
                        .toRotationMatrix();
    PipelineParams p;
    p.preprocess.disableAll();
    p.upd.method = UpdMethod::Fast;
    const PipelineResult r = runPipeline(test::makePlane(1.6, 0.02, pose), p);
    for (std::size_t i = 0; i < r.cloud.size(); ++i) {
      ASSERT_TRUE(r.upd.isValid(i));
      EXPECT_NEAR(r.upd.zeta[i], 1.0, 1e-5);
      EXPECT_NEAR(r.classes.slope_rad[i], tilt_deg * kDegToRad, 2e-3);
    }
  }
}

// On a 2^-10 m grid the cloud moved by 10 km is the same cloud in float: the lattice is anchored
// at the first point, so the fast path gives the same numbers.
TEST(FastUpd, TranslationFarFromOriginChangesNothing) {
  PointCloud c = test::makeRandomCloud(4000, 99, 1.5f);
  for (auto* v : {&c.x, &c.y, &c.z}) {
    for (float& f : *v) f = std::round(f * 1024.f) / 1024.f;
  }
  c.sensor_origin = Eigen::Vector3f(0, 0, 3);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(10240.0, -10240.0, 10240.0);
  PipelineParams p;
  p.preprocess.disableAll();
  p.upd.radius_m = 0.4;
  p.upd.method = UpdMethod::Fast;
  const PipelineResult a = runPipeline(c, p);
  const PipelineResult b = runPipeline(test::transformed(c, T), p);
  ASSERT_EQ(a.upd.size(), b.upd.size());
  for (std::size_t i = 0; i < a.upd.size(); ++i) {
    ASSERT_EQ(a.upd.isValid(i), b.upd.isValid(i));
    if (!a.upd.isValid(i)) continue;
    EXPECT_NEAR(a.upd.zeta[i], b.upd.zeta[i], 1e-5f);
    EXPECT_EQ(a.upd.k[i], b.upd.k[i]);
  }
}

TEST(FastUpd, CostDoesNotDependOnTheRadiusButTheLatticeSizeDoes) {
  // Not a timing: the lattice shrinks as d_m grows, so the work per point cannot grow.
  const Scene s = makeScene("rocks");
  NormalParams np;
  np.radius_m = 0.05;
  const Normals n = computeNormalsGrid(s.cloud, np, s.up);
  std::size_t previous_nodes = std::numeric_limits<std::size_t>::max();
  for (const double d_m : {0.25, 0.5, 1.0, 2.0}) {
    UpdParams p;
    p.radius_m = d_m;
    p.fast_cells_per_point = 0;  // a fixed number of cells per d_m (see the next test)
    FastUpdStats st;
    const UpdResult r = computeUpdFast(s.cloud, n, p, &st);
    EXPECT_EQ(r.size(), s.cloud.size());
    EXPECT_LT(st.nodes, previous_nodes) << "d_m " << d_m;
    previous_nodes = st.nodes;
  }
}

TEST(FastUpd, FinerLatticeKeepsItsCellsWithinTheBudget) {
  // The largest m up to 2 x 4 whose estimated cells (cells at 4 times (m / 4)^2) fit.
  EXPECT_EQ(finerCellsPerRadius(4, 3115, 254345, 0.015), 4);  // 3115 * 1.5625 > 3815
  EXPECT_EQ(finerCellsPerRadius(4, 1000, 150000, 0.015), 6);  // 1000 * 2.25 <= 2250 < 1000 * 3.06
  EXPECT_EQ(finerCellsPerRadius(4, 757, 259845, 0.015), 8);   // 3028 <= 3898: the cap, 2 x 4
  EXPECT_EQ(finerCellsPerRadius(10, 10, 1e6, 0.015), 16);     // never beyond 16
  EXPECT_EQ(finerCellsPerRadius(4, 100, 0, 0.015), 4);        // no valid normal: as given
}

// Rocks sampled every 1 cm (~100 points per occupied 12.5 cm cell), 2 mm noise.
Scene denseRocks() {
  SceneParams sp;
  sp.spacing_m = 0.01;
  sp.noise_m = 0.002;
  return makeScene("rocks", sp);
}

// d_m 0.5 m at 4 cells per d_m on any cloud.
UpdParams fixedLattice() {
  UpdParams p;
  p.radius_m = 0.5;
  p.fast_cells_per_point = 0;
  return p;
}

TEST(FastUpd, DenseCloudsGetAFinerLatticeAndCloserSums) {
  // Rocks sampled every 1 cm (~100 points per occupied 12.5 cm cell) under a budget of 0.03
  // cells per point: a finer lattice, and sums closer to exact. Sampled every 2 cm (~25 points
  // per cell), they keep 4 cells per d_m. (Not every scene improves at every step: an
  // axis-aligned step's error depends on where the cell faces fall, and at 5 or 6 cells per
  // d_m it is larger than at 4; from 7 on it is smaller. Rocks and ramps improve steadily.)
  const Scene dense = denseRocks();
  const Normals normals = exactNormals(dense);
  const UpdParams fixed = fixedLattice();
  UpdParams budget = fixed;
  budget.fast_cells_per_point = 0.03;
  FastUpdStats fs, bs;
  const UpdResult f = computeUpdFast(dense.cloud, normals, fixed, &fs);
  const UpdResult b = computeUpdFast(dense.cloud, normals, budget, &bs);
  EXPECT_EQ(fs.cells_per_radius, 4);
  EXPECT_GT(bs.cells_per_radius, 4);
  const double valid = static_cast<double>(dense.cloud.size() - normals.invalid);
  EXPECT_EQ(bs.cells_per_radius, finerCellsPerRadius(4, fs.cells, valid, 0.03));
  const std::size_t stride = dense.cloud.size() / 3000;
  const Agreement af = agreeWithExact(dense.cloud, normals, f, fixed, dense.up, stride);
  const Agreement ab = agreeWithExact(dense.cloud, normals, b, budget, dense.up, stride);
  EXPECT_LT(ab.mean_abs_dzeta, 0.8 * af.mean_abs_dzeta);
  EXPECT_GE(ab.same_label, af.same_label);

  const Scene sparse = noisyScene("rocks");
  FastUpdStats ss;
  computeUpdFast(sparse.cloud, exactNormals(sparse), budget, &ss);
  EXPECT_EQ(ss.cells_per_radius, 4);
}

TEST(FastUpd, LatticeIsChosenByTheRuleOnTheBaseLatticesCells) {
  // The refinement is decided by counting the base lattice's cells, a sample first, without
  // binning there: for budgets on either side of each step, the lattice is the rule's on the
  // cells of a run at the base lattice, and the result is a run at that lattice's, bit for bit.
  const Scene dense = denseRocks();
  const Normals normals = exactNormals(dense);
  const UpdParams fixed = fixedLattice();
  FastUpdStats fs;
  computeUpdFast(dense.cloud, normals, fixed, &fs);
  const double valid = static_cast<double>(dense.cloud.size() - normals.invalid);
  for (const double budget : {0.002, 0.008, 0.012, 0.02, 0.03, 0.1}) {
    SCOPED_TRACE(budget);
    UpdParams p = fixed;
    p.fast_cells_per_point = budget;
    FastUpdStats ps;
    const UpdResult r = computeUpdFast(dense.cloud, normals, p, &ps);
    const int m = finerCellsPerRadius(4, fs.cells, valid, budget);
    EXPECT_EQ(ps.cells_per_radius, m);
    UpdParams at_m = fixed;
    at_m.fast_cells_per_radius = m;
    const UpdResult e = computeUpdFast(dense.cloud, normals, at_m);
    ASSERT_EQ(r.size(), e.size());
    EXPECT_EQ(std::memcmp(r.zeta.data(), e.zeta.data(), r.zeta.size() * sizeof(float)), 0);
    EXPECT_EQ(std::memcmp(r.rx.data(), e.rx.data(), r.rx.size() * sizeof(float)), 0);
    EXPECT_EQ(r.k, e.k);
  }
}

TEST(FastPaths, DegenerateInputsGiveNaNAndCounts) {
  NormalParams np;
  UpdParams up;
  // Empty.
  const PointCloud empty;
  EXPECT_EQ(computeNormalsGrid(empty, np, Eigen::Vector3f::UnitZ()).size(), 0u);
  EXPECT_EQ(computeUpdFast(empty, Normals{}, up).size(), 0u);
  // All NaN, organized.
  PointCloud nan_image;
  nan_image.resizeOrganized(16, 12);
  const Normals nn = computeNormalsOrganized(nan_image, np, Eigen::Vector3f::UnitZ());
  EXPECT_EQ(nn.invalid, 192u);
  const UpdResult nu = computeUpdFast(nan_image, nn, up);
  EXPECT_EQ(nu.invalid, 192u);
  // Two points: no normal, no UPD.
  PointCloud two;
  two.push_back(0, 0, 0);
  two.push_back(0.01f, 0, 0);
  const Normals tn = computeNormalsGrid(two, np, Eigen::Vector3f::UnitZ());
  EXPECT_EQ(tn.invalid, 2u);
  EXPECT_EQ(computeUpdFast(two, tn, up).invalid, 2u);
  // Sizes must match; knn is not a radius.
  EXPECT_THROW(computeUpdFast(two, Normals{}, up), std::invalid_argument);
  UpdParams knn = up;
  knn.knn = 8;
  EXPECT_THROW(computeUpdFast(two, tn, knn), std::invalid_argument);
  np.knn = 8;
  EXPECT_THROW(computeNormalsGrid(two, np, Eigen::Vector3f::UnitZ()), std::invalid_argument);
  EXPECT_THROW(computeNormalsOrganized(nan_image, np, Eigen::Vector3f::UnitZ()),
               std::invalid_argument);
}

TEST(FastPipeline, MethodRuleIsExplicit) {
  PipelineParams p;
  EXPECT_EQ(resolveMethod(p), UpdMethod::Fast);  // auto, radius neighbourhoods
  p.upd.knn = 16;
  EXPECT_EQ(resolveMethod(p), UpdMethod::Exact);  // auto falls back for knn
  p.upd.method = UpdMethod::Fast;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p = PipelineParams{};
  p.normals.knn = 16;
  p.upd.method = UpdMethod::Fast;
  EXPECT_THROW(p.validate(), std::invalid_argument);
  p.upd.method = UpdMethod::Exact;
  EXPECT_EQ(resolveMethod(p), UpdMethod::Exact);
  p.upd.method = static_cast<UpdMethod>(3);
  EXPECT_THROW(p.validate(), std::invalid_argument);
}

}  // namespace
}  // namespace upd::core
