// The UPD (paper eqs. 6-8) at a cost per point that does not grow with d_m: sums over a
// lattice of voxel moments instead of over every neighbour.
//
// The exact path (upd.h) visits every neighbour within d_m: thousands per point on a Kinect
// frame, and their number grows as d_m^2. This path bins the points into cubic cells of edge
// s = d_m / fast_cells_per_radius and keeps per cell the count of valid normals, their sum and
// the first and second moments of the positions (count, sum p, sum p p^T). The two ball sums
// of eq. 6 (r = sum n_i and k = number of valid normals within d_m) are then evaluated only at
// the lattice nodes (the cell corners) as sums over cells: a cell wholly inside the ball adds
// its sums, a cell wholly outside adds nothing, and a cell that the sphere cuts adds the
// fraction of its points inside, estimated from its moments (the spread of the points along
// the direction to the node, taken as uniform). Every point then takes r and k from the 8
// nodes of its cell by trilinear interpolation corrected with the node gradients (a cubic
// Hermite blend, exact when r and k vary quadratically across the cell), and zeta = |r| / k
// (eq. 8). Optionally (fast_refine_spread > 0), a cell whose nodes disagree on zeta by more
// than that (the ball's edge meets a riser or a wall inside it, where zeta bends sharply) is
// not interpolated: its points get the cell sums at their own position.
//
// Cost: binning and interpolation are O(1) per point (the blend of a cell's nodes is kept as
// the coefficients of its polynomial); a node costs O(fast_cells_per_radius^2) cells (those
// near a surface), and a surface of area A has about 2.5 A / s^2 nodes, so for a fixed
// fast_cells_per_radius the node work falls as d_m grows. The nodes are grouped in blocks of
// (fast_cells_per_radius + 1)^3 cells, whose balls lie in the 27 blocks around; each octant of
// a block sums over the cells within d_m of its part only. Memory is O(points + cells).
// The lattice is anchored at the first finite point: coordinates relative to it are exact in
// float wherever the input floats are, so a cloud 10 km from the origin (UTM) gives the same
// numbers as at the origin.
//
// How far from exact (measured by tests/core/fast_agreement_test.cpp and bench/upd_bench,
// docs/PERFORMANCE.md), at 4 cells per d_m and no refinement: mean |delta zeta|
// 1e-3 to 5e-3 on Kinect frames, a LiDAR scan and generated scenes, labels equal on 98.9-99.97 %
// of the points; the differences gather where zeta crosses zeta_min within a few cm of a sharp
// step. Their number is about the density of points per unit of zeta at zeta_min times the
// mean error there: a cluttered frame with a fifth of its points within 0.01 of zeta_min
// (region_growing) flips the most. With 8 cells per d_m and fast_refine_spread = 0.02 the
// generated scenes agree on >= 99.6 % of the labels, at about 4x the node work. On a plane every
// normal is equal, so r = k n exactly and zeta = 1 at any slope. UpdResult::k is the
// interpolated count rounded to an integer.
//
// A finer lattice where the points are dense (fast_cells_per_point, default 0.015): the cells
// the points occupy at fast_cells_per_radius are counted first (in a sample of the points, then,
// unless the sample already has too many, in all of them); if they number well below
// fast_cells_per_point per point with a valid normal, the points are binned at the largest
// number of cells per d_m, up to twice fast_cells_per_radius, whose cells (estimated as a
// surface's: growing as its square) stay within that budget, else at fast_cells_per_radius. The node work, which follows the
// cells, then stays a fixed share of the per-point work, so the cost per point still does not
// grow with d_m; what grows is the accuracy where a frame is dense. A full-resolution Kinect frame
// of a near scene (region_growing: ~350 points per 12.5 cm cell) gets 8 cells per d_m, and its
// labels agree with the exact path on 99.6 % of the points instead of 98.9 %; a far, wide one
// (office1) keeps 4; a cloud voxelized at 2 cm (a few dozen points per cell) keeps 4.
//
// Exact near the label threshold (fast_exact_band > 0, given the classifier's zeta_min): the
// points whose interpolated zeta lies within the band of zeta_min are summed exactly, over the
// same lattice: a cell wholly inside the ball adds its sums, and the points of a cell the
// sphere cuts are tested one by one (|p - q| <= d_m, as the exact path). Their r, k and zeta
// are then the exact path's (up to the float rounding of a point within ~1e-7 d_m of the
// sphere), and so is their label wherever the interpolation erred by less than the band. The
// cost of such a point is the number of points in the cut cells: ~1 us on a cloud voxelized
// at 2 cm (a few dozen points per cell), ~9 us on a full-resolution Kinect frame (hundreds),
// and it grows with d_m^2 at a fixed density. So the band suits voxelized clouds, LiDAR scans
// and offline scoring; the sensor-rate configuration leaves it off (the default).
#pragma once

#include <cstddef>
#include <limits>

#include "upd/core/normals.h"
#include "upd/core/point_cloud.h"
#include "upd/core/upd.h"

namespace upd::core {

/// Sizes of the lattice, for the benchmark's profile.
struct FastUpdStats {
  std::size_t cells = 0;   ///< occupied lattice cells
  std::size_t nodes = 0;   ///< lattice nodes evaluated
  std::size_t blocks = 0;  ///< groups of (fast_cells_per_radius + 1)^3 cells, the work units
  std::size_t refined_points = 0;  ///< points summed at their own position, not interpolated
  std::size_t exact_points = 0;    ///< points summed exactly (near the label threshold)
  int cells_per_radius = 0;        ///< lattice cells per d_m used (fast_cells_per_point)
};

/// The lattice's cells per d_m for UpdParams::fast_cells_per_point: the largest m from
/// cells_per_radius up to min(2 cells_per_radius, 16) whose occupied cells, estimated as
/// cells (m / cells_per_radius)^2 (a surface), number at most cells_per_point * valid_points.
/// cells: the occupied cells at cells_per_radius; valid_points: the points with a valid normal.
int finerCellsPerRadius(int cells_per_radius, std::size_t cells, double valid_points,
                        double cells_per_point);

/// UPD of every point of cloud from its normals by the lattice of voxel moments described in
/// the header comment. params.knn must be 0 (std::invalid_argument otherwise). The cloud may
/// be organized or not; non-finite points get NaN and are counted in UpdResult::invalid, like
/// points with fewer than params.min_neighbors neighbours (k rounded to the nearest integer).
/// zeta_threshold is the classifier's zeta_min (ClassifyParams): the points whose zeta lies
/// within params.fast_exact_band of it are summed exactly, so that their label is the exact
/// path's. NaN (the default) sums none exactly.
UpdResult computeUpdFast(const PointCloud& cloud, const Normals& normals, const UpdParams& params,
                         FastUpdStats* stats = nullptr,
                         double zeta_threshold = std::numeric_limits<double>::quiet_NaN());

/// The same into out, whose buffers are reused (a frame loop allocates nothing once warm).
void computeUpdFast(const PointCloud& cloud, const Normals& normals, const UpdParams& params,
                    UpdResult& out, FastUpdStats* stats = nullptr,
                    double zeta_threshold = std::numeric_limits<double>::quiet_NaN());

}  // namespace upd::core
