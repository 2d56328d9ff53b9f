// Scoring a fused traversability grid against a ground truth: precision and recall of its
// non-traversable cells.
//
// The truth is any callable giving the true label at a world position (Unknown outside the
// truth's world), so the maps library needs no simulator: a raster read from a ROS map, a
// generated world or a test's lambda all fit. Only cells the map observed (known cells) and
// the truth covers are scored:
//  - precision: of the map's non-traversable cells, the fraction with a truth non-traversable
//    cell within tolerance_m;
//  - recall: of the observed cells the truth marks non-traversable, the fraction with a map
//    non-traversable cell within tolerance_m.
// A match within tolerance_m (cell centres at most that far apart; 0: the same cell) forgives
// the band about d_m wide that the UPD flags around every obstacle (it sums the normals within
// d_m, paper eq. 6).
#pragma once

#include "upd/core/point_cloud.h"
#include "upd/maps/traversability_grid.h"

#include <cstddef>
#include <functional>

namespace upd::maps {

/// The true label at world position (x_m, y_m); Unknown where the truth says nothing.
using TruthLabelAt = std::function<core::Label(double x_m, double y_m)>;

struct MapEvaluation {
  std::size_t map_non_traversable = 0;          ///< scored map cells labelled NonTraversable
  std::size_t map_non_traversable_matched = 0;  ///< ... with a truth obstacle within tolerance
  std::size_t truth_non_traversable = 0;        ///< scored cells the truth marks NonTraversable
  std::size_t truth_non_traversable_found = 0;  ///< ... with a map obstacle within tolerance

  /// matched / map_non_traversable; NaN when the map has no non-traversable cell.
  double precision() const;
  /// found / truth_non_traversable; NaN when the map observed no true obstacle.
  double recall() const;
};

/// Scores grid against truth (sampled at the cell centres) with match distance tolerance_m [m]
/// (>= 0; std::invalid_argument otherwise).
MapEvaluation evaluateGrid(const TraversabilityGrid& grid, const TruthLabelAt& truth,
                           double tolerance_m);

}  // namespace upd::maps
