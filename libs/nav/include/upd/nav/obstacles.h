// What the reactive navigator sees as obstacles: the non-traversable evidence around the robot,
// in the robot frame.
//
// Three sources are merged, each in the world frame until the robot pose maps it to the robot
// frame (p_robot = R(-yaw) (p_world - t)):
//  - the fused traversability grid: the centre of every cell that labelOf() reads as
//    NonTraversable, within range_m of the robot. The map remembers what left the camera's
//    field of view (the camera cannot see the ground right in front of the bumper). The
//    obstacle may fill its cell to the border, where the centre alone lets the polygon's margin
//    overlap it by up to half a cell: with map_cell_border a cell within
//    map_cell_border_range_m of the robot also gives the points of its border every half cell
//    (not thinned by decimation_m). It is off by default: on the navigation benchmark, with the
//    borders at any range, it removes those grazes, but MRPT's reactive navigator, with every
//    obstacle half a cell nearer, stops in more cluttered places than it stops grazing
//    (docs/NAVIGATION.md);
//  - the current frame: every NonTraversable point of the latest scored frame within range_m,
//    so an obstacle acts at once even before the map has fused it (or when the map disagrees);
//  - fixed obstacles: points the caller knows a priori, such as the fence around the mission
//    area (the simulated worlds are bounded; the robot must not leave them);
//  - unobserved ground behind the robot (unobserved_behind_m > 0): the centres of the map's
//    cells more than a cell behind the polygon's rear edge, within unobserved_behind_m of it,
//    that no frame has observed and the robot has not driven on (set by the loop every step).
//    MRPT's navigator has a backward PTG and the camera looks forward: without these its
//    reverses cross ground no sensor checked. (Nearer cells would put obstacle points in the
//    PTGs' first collision-grid cells and stop every motion.) Off by default: on the generated
//    worlds it costs goals (docs/NAVIGATION.md, "Driving a real robot").
// The other sources' points are thinned to one per decimation_m x decimation_m cell (in the
// world frame, so the result does not flicker as the robot turns). Every point carries
// z = point_height_m, which must fall in the navigator's [min_obstacles_height,
// max_obstacles_height] band.
#pragma once

#include "upd/nav/robot_base.h"

#include <Eigen/Core>

#include <cstdint>
#include <unordered_set>
#include <vector>

namespace upd::maps {
class TraversabilityGrid;
}

namespace upd::nav {

/// Loaded from [ObstacleParams].
struct ObstacleParams {
  double range_m = 4.0;           ///< evidence farther than this from the robot is left out [m]
  bool use_map = true;            ///< take NonTraversable cells of the fused grid
  bool map_cell_border = false;   ///< a map cell gives its border too, not only its centre
  double map_cell_border_range_m = 1.0;  ///< ... when its centre is this close to the robot [m]
  bool use_current_frame = true;  ///< take NonTraversable points of the latest frame
  double decimation_m = 0.05;     ///< at most one point per square of this side [m]
  double point_height_m = 0.2;    ///< z of every obstacle point in the robot frame [m]
  double unobserved_behind_m = 0.0;  ///< unobserved ground this close behind the robot is an obstacle [m]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("range_m", range_m, "obstacle evidence within this distance of the robot is used [m]");
    v("use_map", use_map, "use the non-traversable cells of the fused map");
    v("map_cell_border", map_cell_border,
      "a non-traversable map cell gives the points of its border (every half cell) besides its "
      "centre");
    v("map_cell_border_range_m", map_cell_border_range_m,
      "with map_cell_border, only cells whose centre is within this distance of the robot give "
      "their border (a graze is a near obstacle; far borders only narrow the navigator's "
      "choices) [m]");
    v("use_current_frame", use_current_frame, "use the non-traversable points of the latest frame");
    v("decimation_m", decimation_m, "keep at most one obstacle point per square of this side [m]");
    v("point_height_m", point_height_m,
      "z of the obstacle points (inside the navigator's obstacle height band) [m]");
    v("unobserved_behind_m", unobserved_behind_m,
      "map cells behind the robot's rear edge within this distance that no frame observed and the "
      "robot did not drive on are obstacles (the navigator may not reverse onto unseen ground); "
      "0: none [m]");
  }
};

/// p_world expressed in the robot frame of pose_world_robot.
Eigen::Vector2d worldToRobot(const Pose2D& pose_world_robot, const Eigen::Vector2d& p_world);
/// p_robot expressed in the world frame.
Eigen::Vector2d robotToWorld(const Pose2D& pose_world_robot, const Eigen::Vector2d& p_robot);

/// Points every spacing_m (> 0) along the border of the rectangle [min_xy, max_xy].
std::vector<Eigen::Vector2d> rectangleFence(const Eigen::Vector2d& min_xy,
                                            const Eigen::Vector2d& max_xy, double spacing_m);

/// The merged obstacle evidence (see the header comment). Holds a pointer to the grid: the grid
/// must outlive the source or be replaced by setMap.
class ObstacleSource {
 public:
  explicit ObstacleSource(const ObstacleParams& params = {});

  const ObstacleParams& params() const { return params_; }
  /// The fused map to read (nullptr: none).
  void setMap(const maps::TraversabilityGrid* grid) { grid_ = grid; }
  /// Replaces the current frame's NonTraversable points (world frame, xy).
  void setFrameObstacles(std::vector<Eigen::Vector2d> points_world);
  /// Replaces the fixed obstacles (world frame, xy).
  void setFixedObstacles(std::vector<Eigen::Vector2d> points_world);
  /// Replaces the unobserved ground behind the robot (world frame, xy).
  void setUnobservedBehind(std::vector<Eigen::Vector2d> points_world);

  /// Every source within range_m of the robot, thinned, in the robot frame (x forward, y left).
  std::vector<Eigen::Vector2d> pointsInRobot(const Pose2D& pose_world_robot) const;

 private:
  // The map's NonTraversable cells within range (their borders too with map_cell_border).
  void addMapPoints(const Pose2D& pose_world_robot, std::unordered_set<std::uint64_t>& taken_squares,
                    std::vector<Eigen::Vector2d>& out) const;

  ObstacleParams params_;
  const maps::TraversabilityGrid* grid_ = nullptr;
  std::vector<Eigen::Vector2d> frame_world_;
  std::vector<Eigen::Vector2d> fixed_world_;
  std::vector<Eigen::Vector2d> unobserved_world_;
};

}  // namespace upd::nav
