// A traversability map as the figures and the viewer draw it: the 2.5D grid's known cells as
// flat squares at their elevation (or the OctoMap tree's occupied voxels as cubes), coloured by
// the same maps as a cloud (figure.h: zeta = the cell's smallest zeta, label, cost, slope,
// height), the robot's path and the robot at its last pose. `upd render DIR` and `upd view DIR`
// draw a playback folder with it; `upd playback --view` a map while it is built.
#pragma once

#include "upd/nav/figure.h"
#include "upd/maps/traversability_grid.h"
#include "upd/maps/traversability_octree.h"

#include <Eigen/Core>

#include <limits>
#include <string>
#include <vector>

namespace upd::nav {

/// How the map is drawn: the grid's cells, the tree's occupied voxels, or not at all.
enum class MapStyle { Grid, Octree, None };

/// "grid", "octree" or "none"; anything else throws std::invalid_argument.
MapStyle parseMapStyle(const std::string& name);

/// A layer without a value.
inline constexpr float kNoValue = std::numeric_limits<float>::quiet_NaN();

/// One grid cell's layers (NaN when unknown).
struct MapCellView {
  float z = kNoValue, zeta = kNoValue, cost = kNoValue, slope_deg = kNoValue;
  core::Label label = core::Label::Unknown;
};

/// One occupied leaf of the tree.
struct MapVoxelView {
  Eigen::Vector3f centre;
  float size = 0, zeta = kNoValue, cost = kNoValue;
  core::Label label = core::Label::Unknown;
};

/// What is drawn of a map, copied out of the grid and the tree (so the view owns it).
struct MapSnapshot {
  double x_min = 0, y_min = 0, cell_m = 0.1;  ///< the grid's south-west corner and cell size
  int nx = 0, ny = 0;                         ///< cells along x and y
  std::vector<MapCellView> cells;             ///< nx * ny, index cy * nx + cx, cy from y min
  std::vector<MapVoxelView> voxels;
  std::vector<Eigen::Vector3f> path;          ///< the robot's positions [m, world]
  std::vector<Eigen::Vector3f> route;         ///< the planned route ahead, when any [m, world]
  float robot_length_m = 0.7f, robot_width_m = 0.45f;
  /// The robot's heading [rad]; NaN: that of the path's last segment.
  float robot_yaw_rad = std::numeric_limits<float>::quiet_NaN();

  bool hasGrid() const { return nx > 0 && ny > 0; }
  /// The extent of the known cells, voxels and path; false when there is none.
  bool bounds(Eigen::Vector3f& lo, Eigen::Vector3f& hi) const;
};

/// Copies the known cells of grid (labels by its GridParams) into the snapshot's raster.
void snapshotGrid(const maps::TraversabilityGrid& grid, MapSnapshot& out);
/// Copies the tree's occupied leaves (label non-traversable at p >= p_nontrav_threshold).
void snapshotOctree(const maps::TraversabilityOcTree& tree, MapSnapshot& out, double p_nontrav_threshold = 0.65);

/// The robot path of a playback folder's map.3Dscene (its line set); empty when it has none.
/// Throws std::runtime_error when the file cannot be read as an MRPT scene.
std::vector<Eigen::Vector3f> readScenePath(const std::string& scene_file);

/// Draws the map (style), the path, the robot and, when not null, a scored cloud (world frame,
/// z up) to a PNG with the colour bar of options.color; options.up is ignored. Default camera:
/// 55 degrees above the centre of what is drawn, from -x and -y (behind a robot driving +x). Throws when there is nothing to draw.
void renderMapFigure(const MapSnapshot& map, MapStyle style, const ScoredCloud* cloud,
                     const RenderOptions& options, const std::string& png);

}  // namespace upd::nav
