// Private to libs/core: the statistical outlier filter's grid (PointGrid), the cells of its
// search: the finite points binned into cubic cells sized for about (k + 1) / 2 points each, the
// cells numbered by rank in a table of one bit per cell over their box (the hash where that box
// is sparse), the points copied in cell order. preprocess_outliers.cpp searches it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fast_cell_map.h"
#include "fast_cell_ranks.h"
#include "preprocess_internal.h"
#include "upd/core/point_cloud.h"

namespace upd::core::detail {

// Coordinates of the padding: their distances are huge and never kept.
constexpr float kFarPoint = 1e18f;
// The slack of the rows for copyRunByEights.
constexpr std::size_t kCopyLanes = 8;

// The finite points binned into cubic cells of edge h (anchored at the first finite point, as
// the fast UPD's lattice): cell ids from the CellGrid, and the points' coordinates relative
// to the anchor sorted by cell (counting sort), with their cloud indices.
struct PointGrid {
  double h = 1, inv_h = 1;
  float ox = 0, oy = 0, oz = 0;  // anchor
  detail::CellGrid cells;
  std::vector<std::uint32_t> start;  // n_cells + 1
  std::uint32_t max_cell_points = 0;  // the most points in a cell
  std::vector<float> x, y, z;        // by cell (then kCopyLanes of slack)
  std::vector<std::uint32_t> index;  // by cell: the cloud's index
  std::vector<std::uint32_t> cell_of;  // (buildGrid's buffers)
  detail::CellLists by_cell;
  detail::CellCoords coords;

  // Squared distance from (qx, qy, qz) to the box of cell c (0 inside).
  float boxDistance2(std::uint32_t c, float qx, float qy, float qz) const {
    const float q[3] = {qx, qy, qz};
    float d2 = 0.f;
    for (int a = 0; a < 3; ++a) {
      const auto lo = static_cast<float>(xyz(c)[a] * h);
      const auto hi = static_cast<float>((xyz(c)[a] + 1) * h);
      const float d = q[a] < lo ? lo - q[a] : (q[a] > hi ? q[a] - hi : 0.f);
      d2 += d * d;
    }
    // (Shrunk by a rounding margin: a cell is skipped only when it is certainly farther.)
    return d2 * (1.f - 1e-5f);
  }
  std::uint32_t find(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
    return cells.find(cx, cy, cz);
  }

  // The occupied cells by rank over their box widened by kDenseMargin cells on every side, and
  // the shells' cell offsets in it, nearest first: a shell's cells by a load and a population
  // count each instead of a hash look-up. Off (has_dense false) where the table declines the
  // box.
  static constexpr int kDenseMargin = 3;
  bool has_dense = false;
  detail::RankedCells dense;
  detail::TeamCellCounts team_counts;  // (listByCellTeam's)
  std::array<std::vector<std::int64_t>, 4> dense_offsets;  // by ring (0 .. 3)
  // The cells' coordinates, 3 per cell in id order (the ids by rank in the box, or where the
  // table is off in order of first sight, as the hash's CellGrid numbers them).
  std::vector<std::int32_t> cell_xyz;
  std::size_t n_cells = 0;
  const std::int32_t* xyz(std::size_t c) const { return &cell_xyz[3 * c]; }
};

/// The cell offsets at Chebyshev distance ring (0 .. 3), sorted by their distance.
const std::vector<std::array<std::int32_t, 3>>& shellOffsets(int ring);

/// Bins the finite points of in (their indices in finite, not empty) at edge h into g, on the
/// team from CellCoords::kTeamPoints points (the same grid on any number of threads); false when
/// a point lies beyond the keys' range.
bool buildGrid(const PointCloud& in, const std::vector<std::uint32_t>& finite, double h,
               PointGrid& g);

/// The grid's cell edge for the k nearest of the finite points: about (k + 1) / 2 points per
/// occupied cell; coords is left with the points' cells at a first guess.
double gridCellEdge(const PointCloud& in, const std::vector<std::uint32_t>& finite, int k,
                    CellCoords& coords);

}  // namespace upd::core::detail
