// The outlier filter's grid (preprocess_outlier_grid.h): the cell edge, the binning of the
// points into cells numbered by rank (or by the hash), their counting sort and copy, all on the
// team from CellCoords::kTeamPoints points.
#include "preprocess_outlier_grid.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace upd::core::detail {

namespace {

// The cells' rank table (nothing marked) and its shells' offsets over the box [lo, hi] widened
// by kDenseMargin; false (has_dense off) where the table declines the box.
bool makeDense(PointGrid& g, const std::int32_t (&lo)[3], const std::int32_t (&hi)[3],
               std::size_t n_points) {
  g.has_dense = g.dense.reset(lo, hi, PointGrid::kDenseMargin, n_points);
  if (!g.has_dense) return false;
  for (int ring = 0; ring <= PointGrid::kDenseMargin; ++ring) {
    std::vector<std::int64_t>& o = g.dense_offsets[static_cast<std::size_t>(ring)];
    o.clear();
    for (const auto& d : shellOffsets(ring)) o.push_back(g.dense.offset(d[0], d[1], d[2]));
  }
  return true;
}

// Grid points [j0, j1) (cloud points of the cells in id order) copied from the cloud, relative to
// the anchor, with their cloud indices.
void copyByCell(const PointCloud& in, const std::vector<std::uint32_t>& finite, PointGrid& g,
                std::size_t j0, std::size_t j1) {
  for (std::size_t j = j0; j < j1; ++j) {
    const std::uint32_t i = finite[g.by_cell.order[j]];
    g.x[j] = in.x[i] - g.ox, g.y[j] = in.y[i] - g.oy, g.z[j] = in.z[i] - g.oz;
    g.index[j] = i;
  }
}

// The grid's start, the most points in a cell and its point rows sized (kCopyLanes of slack:
// BlockPoints::fill copies 8 at a time), once the points are listed by cell.
void sizeRows(PointGrid& g, std::size_t n_finite) {
  g.start.assign(g.by_cell.start.begin(), g.by_cell.start.end());
  g.max_cell_points = g.by_cell.mostInACell();
  const std::size_t rows = n_finite + kCopyLanes;
  g.x.resize(rows), g.y.resize(rows), g.z.resize(rows);
  for (std::size_t j = n_finite; j < rows; ++j) g.x[j] = g.y[j] = g.z[j] = kFarPoint;
  g.index.resize(n_finite);
}

// Where the grid's cells are numbered by rank: the cells marked, the points listed by cell and
// copied, on the team from kTeamPoints points (the same grid on any number of threads).
void rankAndCopy(const PointCloud& in, const std::vector<std::uint32_t>& finite, PointGrid& g) {
  const std::size_t n = finite.size();
  std::uint32_t* cell_of = g.cell_of.data();
  const CellCoords& k = g.coords;
  const CellRows rows{k.x.data(), k.y.data(), k.z.data(), 1};
#pragma omp parallel if (n >= CellCoords::kTeamPoints)
  {
    // Every point has a cell. (Each thread marks its static share, which the team's marking
    // reads first on the same thread: no barrier, and the share stays in its core's cache.)
    const int team = openmp::teamSize(), me = openmp::threadIndex();
    std::fill(cell_of + RankedCells::share(n, team, me),
              cell_of + RankedCells::share(n, team, me + 1), 0u);
    rankListAndCopyTeam(
        g.dense, rows, n, cell_of, g.by_cell, g.team_counts, g.cell_xyz,
        [&](std::size_t n_cells) { g.n_cells = n_cells, sizeRows(g, n); },
        [&](std::size_t j0, std::size_t j1) { copyByCell(in, finite, g, j0, j1); });
  }
}

}  // namespace

bool buildGrid(const PointCloud& in, const std::vector<std::uint32_t>& finite, double h,
               PointGrid& g) {
  g.h = h, g.inv_h = 1.0 / h;
  const std::uint32_t f0 = finite.front();
  g.ox = in.x[f0], g.oy = in.y[f0], g.oz = in.z[f0];
  std::vector<std::uint32_t>& cell_of = g.cell_of;
  cell_of.resize(finite.size());
  g.coords.compute(in, finite, g.inv_h);
  std::int32_t lo[3], hi[3];
  g.coords.box(lo, hi);
  if (!detail::keyFits(lo[0], lo[1], lo[2]) || !detail::keyFits(hi[0], hi[1], hi[2])) return false;
  if (makeDense(g, lo, hi, finite.size())) {
    rankAndCopy(in, finite, g);
    return true;
  }
  g.cells.clear(finite.size() / 4 + 64);
  const auto coords = [&](std::size_t f, std::int64_t(&c)[3]) {
    c[0] = g.coords.x[f], c[1] = g.coords.y[f], c[2] = g.coords.z[f];
    return true;
  };
  detail::binCells(0, finite.size(), coords, g.cells, cell_of.data());  // (every cell fits)
  g.cell_xyz.assign(g.cells.coords().begin(), g.cells.coords().end());
  g.n_cells = g.cells.size();
  detail::listByCell(
      finite.size(), g.n_cells, [&](std::size_t f) { return cell_of[f]; }, g.by_cell);
  sizeRows(g, finite.size());
  copyByCell(in, finite, g, 0, finite.size());
  return true;
}

const std::vector<std::array<std::int32_t, 3>>& shellOffsets(int ring) {
  static const auto table = [] {
    std::array<std::vector<std::array<std::int32_t, 3>>, 4> t;
    for (std::int32_t r = 0; r < 4; ++r) {
      for (std::int32_t dz = -r; dz <= r; ++dz) {
        for (std::int32_t dy = -r; dy <= r; ++dy) {
          for (std::int32_t dx = -r; dx <= r; ++dx) {
            if (std::max({std::abs(dx), std::abs(dy), std::abs(dz)}) == r) {
              t[static_cast<std::size_t>(r)].push_back({dx, dy, dz});
            }
          }
        }
      }
      std::stable_sort(t[static_cast<std::size_t>(r)].begin(), t[static_cast<std::size_t>(r)].end(),
                       [](const auto& a, const auto& b) {
                         return a[0] * a[0] + a[1] * a[1] + a[2] * a[2] <
                                b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
                       });
    }
    return t;
  }();
  return table[static_cast<std::size_t>(ring)];
}

// About (k + 1) / 2 points per occupied cell: on a surface the k + 1 nearest of a
// point then lie within about 0.8 of a cell's edge, inside the 3 x 3 x 3 block around its cell
// (~120 points on a voxelized Kinect frame) for all but a few per cent of the points, which look
// at the 5 x 5 x 5 block. (With (k + 1) / 3 points more points need the wider block; with
// k + 1 the blocks hold ~210 points: each 5-10 % more instructions on voxelized frames.)
double gridCellEdge(const PointCloud& in, const std::vector<std::uint32_t>& finite, int k,
                    detail::CellCoords& coords) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  const std::size_t n = finite.size();
  // (On the team from kTeamPoints: the box by min and max, the same on any number of threads.)
#pragma omp parallel for if (n > detail::CellCoords::kTeamPoints) schedule(static) \
    reduction(min : lo[:3]) reduction(max : hi[:3])
  for (std::size_t f = 0; f < n; ++f) {
    const std::uint32_t i = finite[f];
    const double p[3] = {in.x[i], in.y[i], in.z[i]};
    for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  }
  const Eigen::Vector3d ext =
      (Eigen::Vector3d(hi[0], hi[1], hi[2]) - Eigen::Vector3d(lo[0], lo[1], lo[2])).cwiseMax(1e-3);
  // First guess: the points filling the bounding box; then one correction from the measured
  // points per occupied cell, as for a surface (count ~ h^2).
  double h = std::cbrt(ext.prod() / static_cast<double>(finite.size()));
  coords.compute(in, finite, 1.0 / h);
  std::int32_t c_lo[3], c_hi[3];
  coords.box(c_lo, c_hi);
  if (!detail::keyFits(c_lo[0], c_lo[1], c_lo[2]) || !detail::keyFits(c_hi[0], c_hi[1], c_hi[2])) {
    return h;  // (buildGrid refuses it too: k-d tree)
  }
  const double per_cell =
      static_cast<double>(finite.size()) / static_cast<double>(coords.countCells(c_lo, c_hi));
  const double target = static_cast<double>(k + 1) / 2.0;
  return h * std::clamp(std::sqrt(target / per_cell), 0.125, 8.0);
}

}  // namespace upd::core::detail
