#include "upd/maps/evaluation.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace upd::maps {

double MapEvaluation::precision() const {
  return map_non_traversable > 0
             ? static_cast<double>(map_non_traversable_matched) / map_non_traversable
             : std::numeric_limits<double>::quiet_NaN();
}

double MapEvaluation::recall() const {
  return truth_non_traversable > 0
             ? static_cast<double>(truth_non_traversable_found) / truth_non_traversable
             : std::numeric_limits<double>::quiet_NaN();
}

namespace {

// Row-major labels of the grid's window, one per cell.
struct CellRaster {
  int nx = 0, ny = 0;
  std::vector<core::Label> label;
  core::Label at(int cx, int cy) const { return label[static_cast<std::size_t>(cy) * nx + cx]; }
};

CellRaster truthRaster(const TraversabilityGrid& grid, const TruthLabelAt& truth) {
  CellRaster r{grid.sizeX(), grid.sizeY(), {}};
  r.label.resize(static_cast<std::size_t>(r.nx) * r.ny);
  for (int cy = 0; cy < r.ny; ++cy) {
    for (int cx = 0; cx < r.nx; ++cx) {
      const Eigen::Vector2d c = grid.cellCenter(cx, cy);
      r.label[static_cast<std::size_t>(cy) * r.nx + cx] = truth(c.x(), c.y());
    }
  }
  return r;
}

CellRaster mapRaster(const TraversabilityGrid& grid) {
  CellRaster r{grid.sizeX(), grid.sizeY(), {}};
  r.label.assign(static_cast<std::size_t>(r.nx) * r.ny, core::Label::Unknown);
  forEachKnownCell(grid, [&](int cx, int cy, const GridCell& cell) {
    r.label[static_cast<std::size_t>(cy) * r.nx + cx] = labelOf(cell, grid.params());
  });
  return r;
}

// True when raster holds a NonTraversable cell whose centre lies within tolerance_m of cell
// (cx, cy)'s.
bool obstacleWithin(const CellRaster& raster, int cx, int cy, int reach_cells, double cell_m,
                    double tolerance_m) {
  for (int dy = -reach_cells; dy <= reach_cells; ++dy) {
    for (int dx = -reach_cells; dx <= reach_cells; ++dx) {
      const int x = cx + dx, y = cy + dy;
      if (x < 0 || y < 0 || x >= raster.nx || y >= raster.ny) continue;
      if (std::hypot(dx, dy) * cell_m > tolerance_m + 1e-9) continue;
      if (raster.at(x, y) == core::Label::NonTraversable) return true;
    }
  }
  return false;
}

}  // namespace

MapEvaluation evaluateGrid(const TraversabilityGrid& grid, const TruthLabelAt& truth,
                           double tolerance_m) {
  if (!(tolerance_m >= 0)) {
    throw std::invalid_argument("evaluateGrid: tolerance_m = " + std::to_string(tolerance_m) +
                                ": must be >= 0");
  }
  const double cell_m = grid.cellSize();
  const int reach = static_cast<int>(std::ceil(tolerance_m / cell_m - 1e-9));
  const CellRaster truth_labels = truthRaster(grid, truth);
  const CellRaster map_labels = mapRaster(grid);
  MapEvaluation e;
  for (int cy = 0; cy < map_labels.ny; ++cy) {
    for (int cx = 0; cx < map_labels.nx; ++cx) {
      const core::Label m = map_labels.at(cx, cy);
      const core::Label t = truth_labels.at(cx, cy);
      if (m == core::Label::Unknown || t == core::Label::Unknown) continue;  // not observed, or no truth
      if (m == core::Label::NonTraversable) {
        ++e.map_non_traversable;
        e.map_non_traversable_matched +=
            obstacleWithin(truth_labels, cx, cy, reach, cell_m, tolerance_m) ? 1 : 0;
      }
      if (t == core::Label::NonTraversable) {
        ++e.truth_non_traversable;
        e.truth_non_traversable_found +=
            obstacleWithin(map_labels, cx, cy, reach, cell_m, tolerance_m) ? 1 : 0;
      }
    }
  }
  return e;
}

}  // namespace upd::maps
