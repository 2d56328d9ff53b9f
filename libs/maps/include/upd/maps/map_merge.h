// Merging and cutting exported maps: the evidence of two maps of the same frame (same world
// frame, same cell size / voxel size) fused as if the frames behind both had been fused into
// one map, and a map cut to a region.
//
// The rule per grid cell (fusion.h's rule applied to whole maps): log-odds add and are clamped
// to [logodds_min, logodds_max]; zeta_min is the minimum; zeta_mean, slope_rad and cost_mean are
// means weighted by the point counts behind them (zeta_count, slope_count, cost_count);
// elevation_m is weighted by hits; elevation_max_m and last_seen_s are maxima; hits and counts
// add. Everything but the log-odds is exactly what fusing both runs' frames gives; the log-odds
// differ from one fusion only where a run's sequence reached a clamp (a cell seen 12 times as
// an obstacle in one run sits at logodds_max there, and one addition cannot know how far past
// the clamp it went), so a merged cell's log-odds is within |logodds_min| + logodds_max of the
// single run's and its label agrees whenever neither run saturated the cell.
//
// Per voxel of the OctoMap tree: occupancy log-odds add (OctoMap's own clamping), the
// traversability log-odds add and clamp, zeta_min is the minimum, cost_mean is weighted by the
// frames behind it (observations), observations add.
#pragma once

#include "upd/maps/fusion.h"
#include "upd/maps/traversability_grid.h"
#include "upd/maps/traversability_octree.h"

#include <cstddef>
#include <cstdint>

namespace upd::maps {

/// The fusion of two cells' evidence (see the header comment); an unobserved cell adds nothing.
GridCell mergeCells(const GridCell& a, const GridCell& b, const FusionParams& fusion);

/// Parameters of a fixed window whose first cell is world cell (i0, j0) and which holds
/// cells_x x cells_y cells (the window is square: the longer side); the thresholds come from base.
GridParams fixedWindowParams(const GridParams& base, std::int64_t i0, std::int64_t j0,
                             std::int64_t cells_x, std::int64_t cells_y);

/// A fixed window (unknown cells) covering the windows of a and b. Throws
/// std::invalid_argument when their cell sizes differ.
TraversabilityGrid windowCovering(const TraversabilityGrid& a, const TraversabilityGrid& b);

/// Fuses every observed cell of from into the cell of into at the same world index; returns
/// the observed cells of from that lie outside into's window (not merged). Throws
/// std::invalid_argument when the cell sizes differ.
std::size_t mergeGridInto(TraversabilityGrid& into, const TraversabilityGrid& from,
                          const FusionParams& fusion);

/// Fuses every leaf of from into into (pruned leaves voxel by voxel), then updates into's inner
/// nodes. Throws std::invalid_argument when the resolutions differ.
void mergeOctreeInto(TraversabilityOcTree& into, const TraversabilityOcTree& from,
                     const FusionParams& fusion);

/// A region of the world plane [m]: [x_min, x_max) x [y_min, y_max).
struct Region {
  double x_min = 0, y_min = 0, x_max = 0, y_max = 0;
};

/// The cells of grid that intersect region, in a fixed window starting at the region's first
/// cell (square: a region that is not square is padded with unknown cells to the east or north;
/// cells outside the region are unknown). Throws std::invalid_argument for an empty region.
TraversabilityGrid cropGrid(const TraversabilityGrid& grid, const Region& region);

/// The voxels of tree whose x and y lie in the region (every z kept).
void cropOctree(TraversabilityOcTree& tree, const Region& region);

}  // namespace upd::maps
