// The fast UPD's interpolation (interpolateFrame: a cell's blend as a polynomial of 20
// monomials, runs of points in one cell evaluated a vector of points at a time, short runs one
// point at a time) against the blend's definition evaluated in double from the 8 nodes: every
// point takes sum_o w_o(f) (v_o + (g_o . (f - o)) / 2), w_o the trilinear weights of corner o,
// v_o and g_o the node's values and gradients. Runs of every length from 1 to 20 points,
// cells whose count falls below min_neighbors (NaN, counted), points without a cell (NaN,
// counted) and a refined cell (left alone). Fixed seeds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "../../libs/core/src/fast_upd_internal.h"

namespace upd::core {
namespace {

using detail::kNoIndex;

TEST(FastUpdInterp, RunsAndSinglePointsFollowTheNodeBlend) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(0.f, 1.f), sym(-1.f, 1.f);
  constexpr int kCells = 6;
  UpdParams params;
  params.min_neighbors = 10;
  PointCloud cloud;
  Normals normals;
  detail::FastFrame f(cloud, normals, params);
  f.lat.rx = 0.5f, f.lat.ry = -2.f, f.lat.rz = 1.f, f.lat.inv_cell = 4.f;  // cells of 0.25 m
  detail::Bins bins;
  detail::FastUpdBuffers buf;
  // Cell c at lattice (c, -c, 2c); 8 nodes of its own, with values and gradients at random;
  // cell 4's counts (k) lie below min_neighbors.
  for (int c = 0; c < kCells; ++c) bins.cellOf(c, -c, 2 * c);
  buf.node_sums.resize(8 * kCells);
  buf.cell_nodes.resize(8 * kCells);
  for (std::size_t v = 0; v < buf.node_sums.size(); ++v) {
    const bool few = v / 8 == 4;
    detail::NodeSums& s = buf.node_sums[v];
    s.q[0] = detail::Quad{30.f * sym(rng), 30.f * sym(rng), 30.f * sym(rng),
                          few ? 2.f + 3.f * unit(rng) : 100.f + 300.f * unit(rng)};
    for (int a = 1; a < 4; ++a) {
      s.q[a] = detail::Quad{5.f * sym(rng), 5.f * sym(rng), 5.f * sym(rng), 10.f * sym(rng)};
    }
    buf.cell_nodes[v] = static_cast<std::uint32_t>(v);
  }
  std::vector<char> refine(kCells, 0);
  refine[5] = 1;
  // Runs of 1 to 20 points, cycling through the cells, a point without a cell between some.
  std::vector<std::uint32_t> cell_of;
  std::vector<Eigen::Vector3f> frac;
  for (int len = 1, run = 0; len <= 20; ++len, ++run) {
    const auto c = static_cast<std::uint32_t>(run % kCells);
    for (int j = 0; j < len; ++j) {
      cell_of.push_back(c);
      frac.emplace_back(unit(rng), unit(rng), unit(rng));
    }
    if (len % 3 == 0) {
      cell_of.push_back(kNoIndex);
      frac.emplace_back(0.f, 0.f, 0.f);
    }
  }
  const std::size_t n = cell_of.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.x.assign(n, nan), cloud.y.assign(n, nan), cloud.z.assign(n, nan);
  for (std::size_t i = 0; i < n; ++i) {
    if (cell_of[i] == kNoIndex) continue;
    const std::int32_t* corner = bins.grid.xyz(cell_of[i]);
    cloud.x[i] = f.lat.rx + (static_cast<float>(corner[0]) + frac[i].x()) / f.lat.inv_cell;
    cloud.y[i] = f.lat.ry + (static_cast<float>(corner[1]) + frac[i].y()) / f.lat.inv_cell;
    cloud.z[i] = f.lat.rz + (static_cast<float>(corner[2]) + frac[i].z()) / f.lat.inv_cell;
  }
  f.chunks = detail::PointChunks::of(cloud, 0);
  f.cell_of = cell_of.data();
  UpdResult out;
  out.rx.assign(n, -7.f), out.ry.assign(n, -7.f), out.rz.assign(n, -7.f);
  out.zeta.assign(n, -7.f), out.k.assign(n, 7u);
  const std::size_t invalid = detail::interpolateFrame(f, bins, buf, refine, out);

  std::size_t want_invalid = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t c = cell_of[i];
    if (c == kNoIndex) {
      ++want_invalid;
      EXPECT_TRUE(std::isnan(out.zeta[i]) && std::isnan(out.rx[i]) && out.k[i] == 0) << i;
      continue;
    }
    if (refine[c]) {  // (its points' values are scoreRefinedCells'; k is left as it was)
      EXPECT_EQ(out.k[i], 7u) << i;
      continue;
    }
    // The point's position in its cell as the stage computes it, then the blend in double.
    const std::int32_t* corner = bins.grid.xyz(c);
    const double fx = f.lat.gx(cloud.x[i]) - static_cast<float>(corner[0]);
    const double fy = f.lat.gy(cloud.y[i]) - static_cast<float>(corner[1]);
    const double fz = f.lat.gz(cloud.z[i]) - static_cast<float>(corner[2]);
    double value[4] = {0, 0, 0, 0};
    for (int o = 0; o < 8; ++o) {
      const int ox = o & 1, oy = (o >> 1) & 1, oz = o >> 2;
      const double w = (ox ? fx : 1 - fx) * (oy ? fy : 1 - fy) * (oz ? fz : 1 - fz);
      const detail::NodeSums& s = buf.node_sums[buf.cell_nodes[8 * c + o]];
      for (int v = 0; v < 4; ++v) {
        const double step = s.q[1][v] * (fx - ox) + s.q[2][v] * (fy - oy) + s.q[3][v] * (fz - oz);
        value[v] += w * (s.q[0][v] + 0.5 * step);
      }
    }
    if (value[3] + 0.5 < params.min_neighbors) {
      ++want_invalid;
      EXPECT_TRUE(std::isnan(out.zeta[i]) && std::isnan(out.rx[i]) && out.k[i] == 0) << i;
      continue;
    }
    const double tol = 1e-4 * (std::abs(value[3]) + 30);
    EXPECT_NEAR(out.rx[i], value[0], tol) << i;
    EXPECT_NEAR(out.ry[i], value[1], tol) << i;
    EXPECT_NEAR(out.rz[i], value[2], tol) << i;
    EXPECT_NEAR(static_cast<double>(out.k[i]), std::round(value[3]), 1.0) << i;
    const double r = std::sqrt(value[0] * value[0] + value[1] * value[1] + value[2] * value[2]);
    EXPECT_NEAR(out.zeta[i], std::min(1.0, r / value[3]), 1e-4) << i;
  }
  EXPECT_EQ(invalid, want_invalid);
  EXPECT_GT(want_invalid, 10u);
}

}  // namespace
}  // namespace upd::core
