// The fast UPD's binning (binFrame: a stripe's runs of points in one cell summed a vector of
// points at a time) against a plain per-point reference: every point lands in the cell of its
// lattice coordinates, every cell's sums (count, normals, positions and their products) are the
// sums over its points in double to float rounding, points without coordinates get no cell,
// and the result is the same bit for bit on one thread and two. Image rows crossing cells in
// runs of every length (one point to several vectors of 8), NaN holes and invalid normals
// inside runs, stripe and chunk boundaries in the middle of a run. Also the chunks every stage
// deals out (equal shares of the finite points), and the whole fast UPD and the grid normals
// the same bit for bit on 1, 2 and 3 threads; the lattice's nodes by rank and by the hash
// name every cell's corners, and the blocks' floor division is the floor of the quotient. Fixed
// seeds.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "../../libs/core/src/fast_upd_internal.h"
#include "synthetic.h"
#include "upd/core/fast_normals.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace upd::core {
namespace {

using detail::kNoIndex;

void setThreads([[maybe_unused]] int n) {
#ifdef _OPENMP
  omp_set_num_threads(n);
#endif
}
using Key = std::tuple<std::int32_t, std::int32_t, std::int32_t>;

// An organized cloud of W x H pixels: rows across a gently curved surface, so that a row
// crosses the cells in runs whose length varies with the row's slope; NaN holes in bursts
// and single pixels, and invalid normals on finite points.
struct Scene {
  PointCloud cloud;
  Normals normals;
};

Scene makeScene(std::size_t W, std::size_t H, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> jitter(-0.002f, 0.002f);
  std::bernoulli_distribution hole(0.03), burst(0.01), no_normal(0.05);
  Scene s;
  s.cloud.resizeOrganized(W, H);
  s.normals = Normals::unset(W * H);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::size_t burst_left = 0;
  for (std::size_t v = 0; v < H; ++v) {
    // The pixel pitch along the row from 0.2 mm to 3 cm: runs of 1 to ~500 points per cell.
    const float pitch = 0.0002f + 0.03f * static_cast<float>(v % 17) / 16.f;
    for (std::size_t u = 0; u < W; ++u) {
      const std::size_t i = v * W + u;
      if (burst(rng)) burst_left = 1 + rng() % 40;
      if (burst_left > 0 || hole(rng)) {
        burst_left -= burst_left > 0 ? 1 : 0;
        s.cloud.x[i] = s.cloud.y[i] = s.cloud.z[i] = nan;
        continue;
      }
      const float x = 3.f + pitch * static_cast<float>(u) + jitter(rng);
      const float y = 0.05f * static_cast<float>(v) + jitter(rng);
      const float z = 0.3f * std::sin(0.7f * x) + 0.1f * std::cos(1.3f * y);
      s.cloud.x[i] = x, s.cloud.y[i] = y, s.cloud.z[i] = z;
      if (no_normal(rng)) continue;
      const Eigen::Vector3f n = Eigen::Vector3f(jitter(rng), 0.2f + jitter(rng), 1.f).normalized();
      s.normals.nx[i] = n.x(), s.normals.ny[i] = n.y(), s.normals.nz[i] = n.z();
    }
  }
  return s;
}

struct Binned {
  detail::Bins bins;
  std::vector<std::uint32_t> cell_of;
  detail::Lattice lat;
};

Binned bin(const Scene& s, const UpdParams& params, int threads) {
  setThreads(threads);
  detail::FastFrame f(s.cloud, s.normals, params);
  f.m = params.fast_cells_per_radius;
  f.lat.inv_cell = static_cast<float>(f.m / params.radius_m);
  std::size_t first = 0;
  while (!s.cloud.isFinite(first)) ++first;
  f.lat.rx = s.cloud.x[first], f.lat.ry = s.cloud.y[first], f.lat.rz = s.cloud.z[first];
  f.chunks = detail::PointChunks::of(s.cloud, first);
  Binned out;
  out.cell_of.assign(s.cloud.size(), kNoIndex);
  f.cell_of = out.cell_of.data();
  detail::binFrame(f, out.bins);
  out.lat = f.lat;
  setThreads(2);
  return out;
}

TEST(FastUpdBins, RunSumsEqualThePerPointSums) {
  UpdParams params;
  params.radius_m = 0.5;
  params.fast_cells_per_radius = 5;
  params.fast_cells_per_point = 0;  // the base lattice only
  // 700 x 300: several chunks of points (about 2^15 finite ones each) and stripes of 256 in
  // every row.
  const Scene s = makeScene(700, 300, 11);
  const Binned one = bin(s, params, 1);
  const Binned two = bin(s, params, 2);

  // The reference: every point's cell from its lattice coordinates (the same float
  // arithmetic), its terms summed in double.
  std::map<Key, std::array<double, 13>> ref;
  const detail::Lattice& lat = one.lat;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    if (!s.cloud.isFinite(i)) {
      ASSERT_EQ(one.cell_of[i], kNoIndex) << "point " << i;
      continue;
    }
    const float gx = lat.gx(s.cloud.x[i]), gy = lat.gy(s.cloud.y[i]), gz = lat.gz(s.cloud.z[i]);
    const float fx = std::floor(gx), fy = std::floor(gy), fz = std::floor(gz);
    const Key key{static_cast<std::int32_t>(fx), static_cast<std::int32_t>(fy),
                  static_cast<std::int32_t>(fz)};
    ASSERT_NE(one.cell_of[i], kNoIndex) << "point " << i;
    const std::int32_t* xyz = one.bins.grid.xyz(one.cell_of[i]);
    ASSERT_EQ(Key(xyz[0], xyz[1], xyz[2]), key) << "point " << i;
    std::array<double, 13>& r = ref[key];
    if (!(s.normals.nx[i] == s.normals.nx[i])) continue;
    const double px = gx - fx, py = gy - fy, pz = gz - fz;
    const double t[13] = {1,       s.normals.nx[i], s.normals.ny[i], s.normals.nz[i], px,
                          py,      pz,              px * px,         px * py,         px * pz,
                          py * py, py * pz,         pz * pz};
    for (int k = 0; k < 13; ++k) r[static_cast<std::size_t>(k)] += t[k];
  }
  ASSERT_EQ(one.bins.sums.size(), ref.size());
  for (std::size_t c = 0; c < one.bins.sums.size(); ++c) {
    const std::int32_t* xyz = one.bins.grid.xyz(c);
    const std::array<double, 13>& r = ref.at(Key(xyz[0], xyz[1], xyz[2]));
    const detail::CellSums& got = one.bins.sums[c];
    const float g[13] = {got.count, got.nx,  got.ny,  got.nz,  got.px,  got.py, got.pz,
                         got.pxx,   got.pxy, got.pxz, got.pyy, got.pyz, got.pzz};
    EXPECT_EQ(static_cast<double>(g[0]), r[0]) << "cell " << c;  // counts are exact
    for (int k = 1; k < 13; ++k) {
      // Float sums of up to a few thousand terms of magnitude <= 1.
      EXPECT_NEAR(g[k], r[static_cast<std::size_t>(k)], 2e-6 * r[0] + 1e-6)
          << "cell " << c << " term " << k;
    }
  }
  // Thread count: the same cells, ids and sums bit for bit.
  ASSERT_EQ(one.cell_of, two.cell_of);
  ASSERT_EQ(one.bins.sums.size(), two.bins.sums.size());
  for (std::size_t c = 0; c < one.bins.sums.size(); ++c) {
    ASSERT_EQ(std::memcmp(&one.bins.sums[c], &two.bins.sums[c], sizeof(detail::CellSums)), 0)
        << "cell " << c;
  }
}

// A scene whose first `sky` rows are NaN, as a camera's above the horizon.
Scene withSky(Scene s, std::size_t sky_rows) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (std::size_t i = 0; i < sky_rows * s.cloud.width; ++i) {
    s.cloud.x[i] = s.cloud.y[i] = s.cloud.z[i] = nan;
  }
  return s;
}

TEST(FastUpdChunks, CoverThePointsInEqualSharesOfTheFiniteOnes) {
  const Scene s = withSky(makeScene(640, 480, 5), 200);
  for (const std::size_t from : {std::size_t(0), std::size_t(1000), std::size_t(150000)}) {
    const detail::PointChunks c = detail::PointChunks::of(s.cloud, from);
    std::size_t first = from;
    while (!s.cloud.isFinite(first)) ++first;
    EXPECT_EQ(c.first_finite, first) << "from " << from;
    ASSERT_EQ(c.count % 4, 0u) << "from " << from;
    ASSERT_EQ(c.bound.size(), c.count + 1);
    EXPECT_EQ(c.begin(0), from);
    EXPECT_EQ(c.end(c.count - 1), s.cloud.size());
    std::vector<std::size_t> finite(c.count, 0);
    std::size_t total = 0;
    for (std::size_t k = 0; k < c.count; ++k) {
      ASSERT_LE(c.begin(k), c.end(k)) << "chunk " << k;
      if (k > 0) {
        EXPECT_EQ(c.begin(k) % 256, 0u) << "chunk " << k;
      }
      for (std::size_t i = c.begin(k); i < c.end(k); ++i) finite[k] += s.cloud.isFinite(i) ? 1 : 0;
      total += finite[k];
    }
    // The cuts fall at the first multiple of 256 where the finite share is reached.
    for (std::size_t k = 0; k < c.count; ++k) {
      EXPECT_NEAR(static_cast<double>(finite[k]), static_cast<double>(total) / c.count, 256.0)
          << "from " << from << ", chunk " << k;
    }
  }
  // No finite point: one chunk, first_finite at the end.
  const Scene sky = withSky(makeScene(300, 20, 5), 20);
  const detail::PointChunks none = detail::PointChunks::of(sky.cloud, 0);
  EXPECT_EQ(none.count, 1u);
  EXPECT_EQ(none.first_finite, sky.cloud.size());
  EXPECT_EQ(none.begin(0), 0u);
  EXPECT_EQ(none.end(0), sky.cloud.size());
}

// The whole fast UPD, its lattice chosen by fast_cells_per_point (the cells counted by the
// team), on a frame with a NaN sky: the same rx, ry, rz, zeta and k bit for bit on 1, 2 and 3
// threads.
TEST(FastUpd, ResultDoesNotDependOnTheThreadCount) {
  const Scene s = withSky(makeScene(640, 480, 9), 150);
  UpdParams params;
  params.radius_m = 0.5;
  params.fast_cells_per_radius = 5;
  params.fast_cells_per_point = 0.5;
  std::vector<UpdResult> results;
  std::vector<int> lattices;
  for (const int threads : {1, 2, 3}) {
    setThreads(threads);
    FastUpdStats stats;
    results.push_back(computeUpdFast(s.cloud, s.normals, params, &stats));
    lattices.push_back(stats.cells_per_radius);
  }
  setThreads(2);
  ASSERT_GT(lattices[0], 5) << "the scene should refine the lattice";
  const UpdResult& one = results[0];
  ASSERT_GT(s.cloud.size() - one.invalid, s.cloud.size() / 2);
  for (std::size_t t = 1; t < results.size(); ++t) {
    const UpdResult& r = results[t];
    EXPECT_EQ(lattices[t], lattices[0]);
    EXPECT_EQ(r.invalid, one.invalid);
    EXPECT_EQ(r.k, one.k);
    for (const auto field : {&UpdResult::rx, &UpdResult::ry, &UpdResult::rz, &UpdResult::zeta}) {
      ASSERT_EQ(std::memcmp((r.*field).data(), (one.*field).data(), sizeof(float) * s.cloud.size()),
                0)
          << "threads " << t + 1;
    }
  }
}

// The blocks' floor division without an integer division: floor(a / b) for negative and
// positive coordinates, multiples of b among them, up to the keys' range.
TEST(FastUpdNodes, FloorDividerIsTheFloorOfTheQuotient) {
  for (const std::int32_t b : {1, 2, 5, 6, 9, 64}) {
    const detail::FloorDivider div(b);
    for (std::int64_t a = -3000; a <= 3000; ++a) {
      ASSERT_EQ(div(static_cast<std::int32_t>(a)),
                static_cast<std::int32_t>(std::floor(static_cast<double>(a) / b)))
          << a << " / " << b;
    }
    for (const std::int32_t a : {-(1 << 21), -(1 << 21) + 1, (1 << 21) - 1, 1 << 21}) {
      ASSERT_EQ(div(a), static_cast<std::int32_t>(std::floor(static_cast<double>(a) / b)))
          << a << " / " << b;
    }
  }
}

// Every cell's 8 corners named by index's ids: each id's coordinates are that corner's, and the
// ids are one per distinct corner, 0 to the count.
void expectCornerNodes(const detail::Bins& bins, const detail::LatticeIndex& index,
                       const std::vector<std::uint32_t>& cell_nodes) {
  std::map<Key, std::uint32_t> node_of;
  const std::size_t n_cells = bins.sums.size();
  ASSERT_EQ(cell_nodes.size(), 8 * n_cells);
  for (std::size_t c = 0; c < n_cells; ++c) {
    for (int o = 0; o < 8; ++o) {
      const std::int32_t* cell = bins.grid.xyz(c);
      const Key corner{cell[0] + (o & 1), cell[1] + ((o >> 1) & 1), cell[2] + ((o >> 2) & 1)};
      const std::uint32_t v = cell_nodes[8 * c + o];
      ASSERT_LT(v, index.nodeCount()) << "cell " << c << ", corner " << o;
      const std::int32_t* xyz = index.nodeXyz(v);
      ASSERT_EQ(Key(xyz[0], xyz[1], xyz[2]), corner) << "cell " << c << ", corner " << o;
      const auto [it, inserted] = node_of.emplace(corner, v);
      ASSERT_EQ(it->second, v) << "one corner, two ids";
    }
  }
  EXPECT_EQ(node_of.size(), index.nodeCount());
}

// The lattice's nodes by rank (on 1, 2 and 3 threads: the same ids) and by the hash name the
// same corners; a far cell makes the box too sparse for the rank table, and the index is then
// the hash's.
TEST(FastUpdNodes, RankAndHashNameEveryCellsCorners) {
  UpdParams params;
  params.radius_m = 0.5;
  params.fast_cells_per_radius = 5;
  Binned b = bin(makeScene(640, 480, 4), params, 2);
  const std::size_t n_cells = b.bins.sums.size();
  ASSERT_GT(n_cells, 1000u);
  const std::int32_t* cells = b.bins.grid.coords().data();
  std::vector<std::uint32_t> first;
  for (const int threads : {1, 2, 3}) {
    SCOPED_TRACE(std::to_string(threads) + " thread(s)");
    setThreads(threads);
    detail::LatticeIndex index;
    std::vector<std::uint32_t> cell_nodes(8 * n_cells);
    ASSERT_TRUE(detail::rankNodes(cells, n_cells, index, cell_nodes.data()));
    expectCornerNodes(b.bins, index, cell_nodes);
    if (first.empty()) first = cell_nodes;
    EXPECT_EQ(cell_nodes, first);
  }
  setThreads(2);
  detail::LatticeIndex hashed;
  std::vector<std::uint32_t> hashed_nodes(8 * n_cells);
  detail::hashNodes(cells, n_cells, hashed, hashed_nodes.data());
  expectCornerNodes(b.bins, hashed, hashed_nodes);

  b.bins.cellOf(cells[0] + 100000, cells[1], cells[2]);  // 10 km away
  detail::LatticeIndex index;
  std::vector<std::uint32_t> unused(8 * (n_cells + 1));
  EXPECT_FALSE(detail::rankNodes(b.bins.grid.coords().data(), n_cells + 1, index, unused.data()));
  std::vector<std::uint32_t> cell_nodes;
  detail::indexLattice(b.bins, params.fast_cells_per_radius, index, cell_nodes);
  expectCornerNodes(b.bins, index, cell_nodes);
}

// The grid normals of an unorganized cloud (its binning on the team from 16,384 points), with
// NaN points: the same normals and curvatures bit for bit on 1, 2 and 3 threads; a cloud
// spanning more than 2^20 radii is refused by name on two threads as on one.
TEST(FastNormalsGrid, ResultDoesNotDependOnTheThreadCount) {
  PointCloud c = test::makeRandomCloud(40000, 21, 2.f);
  for (std::size_t i = 5; i < c.size(); i += 997) c.y[i] = std::numeric_limits<float>::quiet_NaN();
  c.sensor_origin = Eigen::Vector3f(0, 0, 3);
  NormalParams p;
  p.radius_m = 0.08;
  std::vector<Normals> results;
  for (const int threads : {1, 2, 3}) {
    setThreads(threads);
    results.push_back(computeNormalsGrid(c, p, Eigen::Vector3f::UnitZ()));
  }
  const Normals& one = results[0];
  ASSERT_GT(c.size() - one.invalid, c.size() / 2);
  for (std::size_t t = 1; t < results.size(); ++t) {
    EXPECT_EQ(results[t].invalid, one.invalid);
    for (std::size_t i = 0; i < c.size(); ++i) {
      ASSERT_EQ(results[t].isValid(i), one.isValid(i)) << "threads " << t + 1 << ", point " << i;
      if (!one.isValid(i)) continue;
      ASSERT_EQ(results[t].normal(i), one.normal(i)) << "threads " << t + 1 << ", point " << i;
      ASSERT_EQ(results[t].curvature[i], one.curvature[i]) << "threads " << t + 1;
    }
  }
  c.x[30000] = 1e6f;  // (1e6 m / 0.08 m: beyond the keys' 2^20 cells)
  for (const int threads : {1, 2}) {
    setThreads(threads);
    try {
      computeNormalsGrid(c, p, Eigen::Vector3f::UnitZ());
      ADD_FAILURE() << "a cloud beyond the keys' range was accepted on " << threads << " thread(s)";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("NormalParams.radius_m"), std::string::npos) << e.what();
    }
  }
  setThreads(2);
}

}  // namespace
}  // namespace upd::core
