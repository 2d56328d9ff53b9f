// The one cell-binning helper of the core (CellGrid, binCells, listByCell: the fast UPD's
// lattice, the grid normals and the pre-processing grids) against brute force on random clouds:
// every point lands in the cell of its coordinates, distinct cells get distinct ids, and the
// cell lists partition the points in their order.
#include "../../libs/core/src/fast_cell_map.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <tuple>
#include <vector>

namespace upd::core {
namespace {

using Cell = std::tuple<std::int64_t, std::int64_t, std::int64_t>;

struct RandomCloud {
  std::vector<double> x, y, z;
  std::vector<bool> valid;  // a point without a cell (as a non-finite one)
};

RandomCloud randomCloud(std::size_t n, double extent, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-extent, extent);
  std::bernoulli_distribution missing(0.1);
  RandomCloud c;
  for (std::size_t i = 0; i < n; ++i) {
    c.x.push_back(u(rng)), c.y.push_back(u(rng)), c.z.push_back(u(rng));
    c.valid.push_back(!missing(rng));
  }
  return c;
}

Cell cellOf(const RandomCloud& c, std::size_t i, double edge) {
  return {static_cast<std::int64_t>(std::floor(c.x[i] / edge)),
          static_cast<std::int64_t>(std::floor(c.y[i] / edge)),
          static_cast<std::int64_t>(std::floor(c.z[i] / edge))};
}

TEST(CellBins, EveryPointLandsInTheCellOfItsCoordinates) {
  for (const std::uint32_t seed : {1u, 2u, 3u}) {
    const double edge = 0.05 * seed;
    const RandomCloud cloud = randomCloud(5000, 1.0, seed);
    const std::size_t n = cloud.x.size();
    detail::CellGrid grid;
    std::vector<std::uint32_t> cell_of(n, 12345);
    const auto coords = [&](std::size_t i, std::int64_t(&c)[3]) {
      if (!cloud.valid[i]) return false;
      std::tie(c[0], c[1], c[2]) = cellOf(cloud, i, edge);
      return true;
    };
    ASSERT_TRUE(detail::binCells(0, n, coords, grid, cell_of.data()));

    // Brute force: the distinct cells in order of first sight.
    std::map<Cell, std::uint32_t> expected_id;
    for (std::size_t i = 0; i < n; ++i) {
      if (!cloud.valid[i]) {
        EXPECT_EQ(cell_of[i], detail::kNoIndex);
        continue;
      }
      const Cell cell = cellOf(cloud, i, edge);
      const auto it = expected_id.emplace(cell, static_cast<std::uint32_t>(expected_id.size()));
      ASSERT_EQ(cell_of[i], it.first->second) << "point " << i;
      const std::int32_t* xyz = grid.xyz(cell_of[i]);
      EXPECT_EQ(Cell(xyz[0], xyz[1], xyz[2]), cell);
    }
    ASSERT_EQ(grid.size(), expected_id.size());
    for (const auto& [cell, id] : expected_id) {
      EXPECT_EQ(grid.find(std::get<0>(cell), std::get<1>(cell), std::get<2>(cell)), id);
    }
    // An empty cell and one beyond the key range are not found.
    EXPECT_EQ(grid.find(1000, 1000, 1000), detail::kNoIndex);
    EXPECT_EQ(grid.find(detail::kKeyBias, 0, 0), detail::kNoIndex);

    // The lists partition the points with a cell, each list in point order.
    detail::CellLists lists;
    detail::listByCell(
        n, grid.size(), [&](std::size_t i) { return cell_of[i]; }, lists);
    ASSERT_EQ(lists.start.size(), grid.size() + 1);
    std::vector<int> seen(n, 0);
    std::uint32_t most = 0;
    for (std::size_t c = 0; c < grid.size(); ++c) {
      EXPECT_FALSE(lists.empty(c));
      most = std::max(most, lists.start[c + 1] - lists.start[c]);
      for (std::uint32_t q = lists.start[c]; q < lists.start[c + 1]; ++q) {
        const std::uint32_t i = lists.order[q];
        EXPECT_EQ(cell_of[i], c);
        if (q > lists.start[c]) {
          EXPECT_LT(lists.order[q - 1], i);
        }
        ++seen[i];
      }
    }
    for (std::size_t i = 0; i < n; ++i) EXPECT_EQ(seen[i], cloud.valid[i] ? 1 : 0) << i;
    EXPECT_EQ(lists.mostInACell(), most);  // (the room of the blocks copied from the lists)
  }
}

TEST(CellBins, RefusesCellsBeyondTheKeyRange) {
  detail::CellGrid grid;
  std::vector<std::uint32_t> cell_of(3, 0);
  const std::int64_t x[3] = {0, detail::kKeyBias, 1};
  const auto coords = [&](std::size_t i, std::int64_t(&c)[3]) {
    c[0] = x[i], c[1] = 0, c[2] = 0;
    return true;
  };
  EXPECT_FALSE(detail::binCells(0, 3, coords, grid, cell_of.data()));
  EXPECT_EQ(grid.size(), 1u);  // the first point's cell only
  EXPECT_TRUE(detail::binCells(0, 1, coords, grid, cell_of.data()));
  EXPECT_EQ(grid.find(-detail::kKeyBias, 0, 0), detail::kNoIndex);
}

TEST(CellBins, EmptyInput) {
  detail::CellGrid grid;
  EXPECT_TRUE(detail::binCells(
      0, 0, [](std::size_t, std::int64_t(&)[3]) { return true; }, grid, nullptr));
  detail::CellLists lists;
  detail::listByCell(
      0, 0, [](std::size_t) { return detail::kNoIndex; }, lists);
  EXPECT_EQ(lists.start.size(), 1u);
  EXPECT_TRUE(lists.order.empty());
  EXPECT_EQ(lists.mostInACell(), 0u);
}

}  // namespace
}  // namespace upd::core
