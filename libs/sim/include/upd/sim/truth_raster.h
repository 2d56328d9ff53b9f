// The ground truth of a world rasterised: Terrain::truthAt at the centre of every cell_m cell
// over the terrain's extent. The one truth raster of the project: the navigation loop checks
// collisions and clearance against it, `upd simulate` writes it beside its rawlog (as a ROS
// map_server map through upd/io/ros_map.h), and the planner of the simulated run plans on it.
//
// A footprint collides when a NonTraversable cell centre lies inside it; its clearance is the
// distance from the footprint rectangle to the nearest NonTraversable cell centre (0 when
// colliding), searched up to search_m beyond the footprint (farther: search_m).
#pragma once

#include "upd/core/point_cloud.h"
#include "upd/sim/robot.h"
#include "upd/sim/terrain.h"

#include <Eigen/Core>

#include <vector>

namespace upd::sim {

class TruthRaster {
 public:
  /// Throws std::invalid_argument for cell_m <= 0 or not finite.
  TruthRaster(const Terrain& terrain, double cell_m);

  double cellSize() const { return cell_m_; }  ///< [m/cell]
  int sizeX() const { return nx_; }
  int sizeY() const { return ny_; }
  /// The lower-left corner of cell (0, 0) in the world (the terrain's minXY) [m].
  const Eigen::Vector2d& origin() const { return min_xy_; }
  core::Label at(int ix, int iy) const { return labels_[static_cast<std::size_t>(iy) * nx_ + ix]; }
  /// Row-major from the bottom row (iy = 0), sizeX() * sizeY().
  const std::vector<core::Label>& labels() const { return labels_; }
  Eigen::Vector2d cellCenter(int ix, int iy) const;

  /// pose_world_robot is planar: (x [m], y [m], yaw [rad]).
  bool collides(const Eigen::Vector3d& pose_world_robot, const RobotBodyParams& body) const;
  double clearance(const Eigen::Vector3d& pose_world_robot, const RobotBodyParams& body,
                   double search_m) const;

 private:
  Eigen::Vector2d min_xy_;
  double cell_m_;
  int nx_ = 0, ny_ = 0;
  std::vector<core::Label> labels_;
};

}  // namespace upd::sim
