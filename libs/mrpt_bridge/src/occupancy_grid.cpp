#include "upd/mrpt_bridge/occupancy_grid.h"

#include <cmath>

namespace upd::mrpt_bridge {

mrpt::maps::COccupancyGridMap2D toOccupancyGrid(const maps::TraversabilityGrid& grid) {
  const float res = static_cast<float>(grid.cellSize());
  mrpt::maps::COccupancyGridMap2D occ(
      static_cast<float>(grid.xMin()), static_cast<float>(grid.xMax()),
      static_cast<float>(grid.yMin()), static_cast<float>(grid.yMax()), res);
  occ.fill(0.5f);
  // MRPT keeps its limits in float: map each cell by its centre, half a cell from any edge, so
  // float rounding of the limits cannot shift a cell into its neighbour.
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    for (int cx = 0; cx < grid.sizeX(); ++cx) {
      const float p = maps::probabilityOf(grid.at(cx, cy), grid.params());
      if (std::isnan(p)) continue;
      const Eigen::Vector2d c = grid.cellCenter(cx, cy);
      const int ox = static_cast<int>(std::floor((c.x() - occ.getXMin()) / occ.getResolution()));
      const int oy = static_cast<int>(std::floor((c.y() - occ.getYMin()) / occ.getResolution()));
      occ.setCell(ox, oy, p);  // ignores indices outside the MRPT grid
    }
  }
  return occ;
}

}  // namespace upd::mrpt_bridge
