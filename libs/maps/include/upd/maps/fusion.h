// Fusing per-point traversability over time: the input view and the log-odds rule shared by the
// 2.5D grid and the OctoMap tree.
//
// A frame's scored points (world frame, z up) are viewed, not copied: PointsWorld holds const
// pointers into the caller's arrays (a PointCloud transformed to the world frame, and the
// Classification / UpdResult of the pipeline run on it).
//
// The rule (binary Bayes filter in log-odds, as in OctoMap and MRPT's occupancy grids): the points
// of one frame that fall in one cell (or voxel) are first aggregated, then the cell gets ONE
// update for the frame, never one per point (a dense cloud would otherwise saturate a cell from a
// single view):
//  - only Traversable and NonTraversable points count; Unknown points and points with
//    non-finite coordinates are ignored (they are counted, nothing else);
//  - a cell with fewer than min_points_per_cell labelled points in the frame is not updated;
//  - if the fraction of its labelled points that are NonTraversable is >= nontrav_fraction, the
//    cell gets the hit update logodds_hit (evidence for non-traversable), otherwise the miss
//    update logodds_miss (evidence for traversable);
//  - L starts at 0 (p = 0.5) on the first observation and is clamped to
//    [logodds_min, logodds_max] after every update.
// Clamping is what makes the map revisable: with the defaults an obstacle seen in 5 frames sits
// at L = 3.5 (p = 0.97), a single contradicting frame takes it to 3.1 (p = 0.96), still
// non-traversable, while a false alarm seen once (L = 0.85, p = 0.70) falls below p = 0.5 after
// three traversable frames. Cells not observed in a frame are left unchanged (no decay).
#pragma once

#include "upd/core/classify.h"
#include "upd/core/params.h"
#include "upd/core/point_cloud.h"
#include "upd/core/upd.h"

#include <cmath>
#include <cstddef>

namespace upd::maps {

/// A non-owning view of one frame's scored points in the world frame (z up). x, y, z and label
/// are required (when size > 0); zeta, slope_rad and cost may be null (their layers then stay
/// NaN). All arrays hold size entries and must outlive the call they are passed to.
struct PointsWorld {
  const float* x = nullptr;  ///< [m], world frame
  const float* y = nullptr;  ///< [m], world frame
  const float* z = nullptr;  ///< [m], world frame, up
  const core::Label* label = nullptr;
  const float* zeta = nullptr;       ///< UPD zeta [-]; NaN where not scored
  const float* slope_rad = nullptr;  ///< slope of r [rad]; NaN where not scored
  const float* cost = nullptr;       ///< traversal cost [0, 1]; NaN where unknown
  std::size_t size = 0;

  /// Throws std::invalid_argument when a required array is null and size > 0.
  void validate() const;
};

/// Views cloud_world (already transformed to the world frame) with the classification computed
/// on it and, optionally, its UPD (for zeta). Throws std::invalid_argument when the sizes differ.
PointsWorld viewPoints(const core::PointCloud& cloud_world, const core::Classification& classes,
                       const core::UpdResult* upd = nullptr);

/// The log-odds fusion rule; see the header comment. Loaded from the [FusionParams] ini section.
struct FusionParams {
  double logodds_hit = 0.85;   ///< added when a frame sees the cell as non-traversable (p 0.7)
  double logodds_miss = -0.4;  ///< added when a frame sees the cell as traversable (p 0.4)
  double logodds_min = -2.0;   ///< lower clamp (p 0.12): a traversable cell can still turn
  double logodds_max = 3.5;    ///< upper clamp (p 0.97): an obstacle can still be revised
  /// A frame sees a cell as non-traversable when at least this fraction of its labelled points
  /// are NonTraversable (0.25: an edge cell half ground, half rock counts as a hit; one stray
  /// point among forty ground points does not).
  double nontrav_fraction = 0.25;
  int min_points_per_cell = 1;  ///< fewer labelled points in a frame: no update for the cell

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("logodds_hit", logodds_hit, "log-odds added per frame that sees a cell non-traversable");
    v("logodds_miss", logodds_miss, "log-odds added per frame that sees a cell traversable (< 0)");
    v("logodds_min", logodds_min, "lower clamp of the log-odds (< 0)");
    v("logodds_max", logodds_max, "upper clamp of the log-odds (> 0)");
    v("nontrav_fraction", nontrav_fraction,
      "fraction of a cell's labelled points that must be non-traversable for a hit (0..1]");
    v("min_points_per_cell", min_points_per_cell,
      "labelled points a cell needs in one frame to be updated (>= 1)");
  }
};

/// The frame update for a cell with these labelled-point counts: logodds_hit, logodds_miss, or
/// 0 when the cell has too few labelled points (not observed in this frame).
double frameLogOddsUpdate(std::size_t n_nontraversable, std::size_t n_traversable,
                          const FusionParams& params);

/// L' = clamp((isnan(L) ? 0 : L) + update, logodds_min, logodds_max).
float fuseLogOdds(float logodds, double update, const FusionParams& params);

/// p = 1 / (1 + exp(-L)); NaN stays NaN (never observed).
inline float probabilityFromLogOdds(float logodds) { return 1.0f / (1.0f + std::exp(-logodds)); }

}  // namespace upd::maps
