// The team's cell helpers of the outlier filter's grid and the grid normals (RankedCells,
// listByCellTeam) against brute force, on 1, 2 and 3 threads: a cell's id is the number of
// occupied cells before it in the box, an empty cell has none, the ids of three neighbours along
// x at once are those of one at a time (also where they straddle two words of the table); a box
// of too many cells per point is declined; the team's lists are the one-thread counting sort's,
// item for item; the team's coordinates of every id are its cell's. Fixed seeds.
#include "../../libs/core/src/fast_cell_ranks.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

namespace upd::core {
namespace {

using detail::kNoIndex;

// RankedCells over the box [0, 31) x [0, 20) x [0, 10) (margin 1: rows of 33 cells, so that the
// table's words start at every x) with the cells at index_of marked, built by a team of
// `threads`.
detail::RankedCells build(const std::vector<std::size_t>& index_of, int threads) {
  detail::RankedCells r;
  const std::int32_t lo[3] = {0, 0, 0}, hi[3] = {30, 19, 9};
  EXPECT_TRUE(r.reset(lo, hi, 1, 3000));  // (sized as for 3000 points: never declined)
#pragma omp parallel num_threads(threads)
  r.buildTeam(index_of.size(), [&](std::size_t i) { return index_of[i]; });
  return r;
}

TEST(RankedCells, IdsAreTheOccupiedCellsBeforeInTheBoxOnAnyTeam) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::int32_t> x(0, 30), y(0, 19), z(0, 9);
  const std::size_t box = 33 * 22 * 12;  // (the box widened by the margin)
  for (const std::size_t n : {0u, 1u, 40u, 3000u}) {
    std::vector<std::size_t> index_of;
    std::vector<bool> marked(box, false);
    detail::RankedCells probe;
    const std::int32_t lo[3] = {0, 0, 0}, hi[3] = {30, 19, 9};
    ASSERT_TRUE(probe.reset(lo, hi, 1, 3000));
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t b = probe.index(x(rng), y(rng), z(rng));
      index_of.push_back(b);
      marked[b] = true;
    }
    for (const int threads : {1, 2, 3}) {
      SCOPED_TRACE(std::to_string(n) + " points, " + std::to_string(threads) + " thread(s)");
      const detail::RankedCells r = build(index_of, threads);
      std::uint32_t before = 0;
      for (std::size_t b = 0; b < box; ++b) {
        ASSERT_EQ(r.id(b), marked[b] ? before : kNoIndex) << "cell " << b;
        before += marked[b] ? 1 : 0;
      }
      EXPECT_EQ(r.size(), before);
      for (std::size_t b = 0; b + 3 <= box; ++b) {
        std::uint32_t three[3];
        r.threeIds(b, three);
        for (std::size_t k = 0; k < 3; ++k) ASSERT_EQ(three[k], r.id(b + k)) << "cell " << b + k;
      }
    }
  }
}

TEST(RankedCells, TheTeamGivesEveryIdItsCellsCoordinates) {
  // (A box of negative coordinates, without and with a margin: cellAt undoes index.)
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::int32_t> x(-40, -3), y(-7, 12), z(-300, -290);
  for (const int margin : {0, 2}) {
    for (const std::size_t n : {0u, 1u, 50u, 4000u}) {
      detail::RankedCells r;
      const std::int32_t lo[3] = {-40, -7, -300}, hi[3] = {-3, 12, -290};
      ASSERT_TRUE(r.reset(lo, hi, margin, 4000));
      std::vector<std::int32_t> cells;
      for (std::size_t i = 0; i < n; ++i) cells.insert(cells.end(), {x(rng), y(rng), z(rng)});
      for (const int threads : {1, 2, 3}) {
        SCOPED_TRACE(std::to_string(n) + " points, margin " + std::to_string(margin) + ", " +
                     std::to_string(threads) + " thread(s)");
        std::vector<std::int32_t> xyz;
#pragma omp parallel num_threads(threads)
        {
          r.buildTeam(n, [&](std::size_t i) {
            return r.index(cells[3 * i], cells[3 * i + 1], cells[3 * i + 2]);
          });
#pragma omp single
          xyz.assign(3 * r.size(), 0);
          r.cellsTeam(xyz.data());
        }
        for (std::size_t i = 0; i < n; ++i) {  // every marked cell: its id's coordinates
          const std::uint32_t id = r.id(r.index(cells[3 * i], cells[3 * i + 1], cells[3 * i + 2]));
          ASSERT_NE(id, kNoIndex);
          for (int a = 0; a < 3; ++a) ASSERT_EQ(xyz[3 * id + a], cells[3 * i + a]) << "cell " << i;
        }
        for (std::uint32_t id = 0; id < r.size(); ++id) {  // and every id is a marked cell's
          ASSERT_EQ(r.id(r.index(xyz[3 * id], xyz[3 * id + 1], xyz[3 * id + 2])), id);
          std::int32_t back[3];
          r.cellAt(r.index(xyz[3 * id], xyz[3 * id + 1], xyz[3 * id + 2]), back);
          for (int a = 0; a < 3; ++a) ASSERT_EQ(back[a], xyz[3 * id + a]);
        }
      }
    }
  }
}

TEST(RankedCells, DeclinesABoxOfTooManyCellsPerPoint) {
  detail::RankedCells r;
  const std::int32_t lo[3] = {0, 0, 0}, hi[3] = {999, 999, 9};  // 10^7 cells
  EXPECT_FALSE(r.reset(lo, hi, 0, 100));
  EXPECT_TRUE(r.reset(lo, hi, 0, 1000000));
}

TEST(ListByCellTeam, ListsAreTheOneThreadCountingSortsOnAnyTeam) {
  std::mt19937 rng(9);
  for (const std::size_t n_cells : {0u, 1u, 7u, 500u}) {
    for (const std::size_t n_items : {0u, 1u, 33u, 20000u}) {
      std::vector<std::uint32_t> cell(n_items);
      std::uniform_int_distribution<std::uint32_t> pick(0, n_cells == 0 ? 0 : n_cells - 1);
      for (std::uint32_t& c : cell) c = n_cells == 0 || rng() % 5 == 0 ? kNoIndex : pick(rng);
      const auto cell_of = [&](std::size_t i) { return cell[i]; };
      detail::CellLists want;
      detail::listByCell(n_items, n_cells, cell_of, want);
      detail::CellLists got;
      detail::TeamCellCounts counts;
      for (const int threads : {1, 2, 3}) {
        SCOPED_TRACE(std::to_string(n_cells) + " cells, " + std::to_string(n_items) +
                     " items, " + std::to_string(threads) + " thread(s)");
#pragma omp parallel num_threads(threads)
        detail::listByCellTeam(n_items, n_cells, cell_of, got, counts);
        EXPECT_EQ(got.start, want.start);
        EXPECT_EQ(got.order, want.order);
      }
    }
  }
}

}  // namespace
}  // namespace upd::core
