// A simulated robot run recorded as a real MRPT rawlog: the embedded default data of UPD-Nav.
//
// A virtual robot (sim::RobotBodyParams and sim::CameraMountParams, upd/sim/robot.h: the Dune
// with a Kinect at its front, pitched down) drives through a generated
// world (upd/sim/terrain.h): from the world's start to its goal and back, along a route planned
// on the ground truth with the robot's clearance (the one grid planner, upd/maps/grid_planner.h).
// Its body follows the terrain (sim::bodyPoseOnTerrain: pitch and roll from the wheel contact
// heights, so it tilts on the ramp). Every frame_spacing_m it records a CObservation3DRangeScan
// rendered by ray casting with Kinect noise (upd/sim/render.h), preceded by a
// CActionRobotMovement2D odometry increment with drift. Beside the rawlog it writes the
// ground-truth poses (TUM: t x y z qx qy qz qw) and the world's ground-truth traversability
// raster (sim::TruthRaster as a ROS map_server PGM + YAML, upd/io/ros_map.h).
#pragma once

#include "upd/core/params.h"
#include "upd/sim/robot.h"

#include <Eigen/Geometry>

#include <string>
#include <vector>

namespace upd::sim {
class TruthRaster;
struct WorldSpec;
}  // namespace upd::sim

namespace upd::mrpt_bridge {

struct SimulationParams {
  sim::RobotBodyParams body;           ///< loaded from [RobotBodyParams]
  sim::CameraMountParams camera;       ///< loaded from [CameraMountParams]
  double speed_mps = 0.4;              ///< driving speed, sets the timestamps [m/s]
  double frame_spacing_m = 0.2;        ///< distance driven between frames [m]
  double clearance_m = 0.45;           ///< route keeps this far from non-traversable truth [m]
  double odometry_sigma_ratio = 0.02;  ///< odometry distance noise, fraction of the step [-]
  double odometry_yaw_bias_rad_per_m = 0.5 * core::kDegToRad;  ///< odometry heading drift [rad/m]
  double truth_cell_m = 0.05;                            ///< cell of the ground-truth grid [m]
  int seed = 1;
  bool return_to_start = true;  ///< drive back to the start after the goal
  /// > 0: drive this far [m], repeating the world's closed course (or start -> goal -> start)
  /// as often as needed; 0: the route once.
  double distance_m = 0.0;

  /// Validates this section and the body and camera (std::invalid_argument naming the field).
  void validate() const;
  /// The keys of [SimulationParams]; body and camera are sections of their own.
  template <class V>
  void visit(V& v) {
    v("speed_mps", speed_mps, "driving speed [m/s]");
    v("frame_spacing_m", frame_spacing_m, "distance between recorded frames [m]");
    v("clearance_m", clearance_m, "route clearance from non-traversable ground truth [m]");
    v("odometry_sigma_ratio", odometry_sigma_ratio, "odometry noise per step, fraction [-]");
    v.angleDeg("odometry_yaw_bias_deg_per_m", odometry_yaw_bias_rad_per_m,
               "odometry heading drift [deg/m]");
    v("truth_cell_m", truth_cell_m, "cell of the ground-truth traversability grid [m]");
    v("seed", seed, "noise seed");
    v("return_to_start", return_to_start, "drive back to the start after reaching the goal");
    v("distance_m", distance_m,
      "> 0: drive this far, repeating the world's course (laps); 0: the route once [m]");
  }
};

/// A pose of the simulated route.
struct RoutePose {
  double t_s = 0;
  Eigen::Isometry3d pose_world_robot = Eigen::Isometry3d::Identity();
  double yaw_rad = 0;  ///< heading in the world frame
};

/// The route of a simulated run through the world, planned on the ground truth (0.1 m cells,
/// the world's border blocked, clearance_m kept from non-traversable or unknown truth) and
/// straightened: start -> goal (-> start), or round the world's course (WorldSpec::course) back
/// to start; with distance_m > 0 the closed route repeated and cut at distance_m; poses every frame_spacing_m with the body resting on the terrain, turning in
/// place (15 deg steps) at the corners. Throws std::invalid_argument naming the world when the
/// start or the goal lacks the clearance or the goal cannot be reached.
std::vector<RoutePose> planSimulatedRoute(const sim::WorldSpec& world, const SimulationParams& p);

struct SimulationSummary {
  std::size_t frames = 0;
  double path_length_m = 0;
  double duration_s = 0;
  std::string rawlog_path, poses_path, truth_yaml_path;
};

/// Writes rawlog_path (gzip MRPT rawlog, actions + sensory frames), <stem>.gt.tum and
/// <stem>.truth.pgm/.yaml beside it; every file through a temporary file and a rename.
SimulationSummary simulateRun(const sim::WorldSpec& world, const SimulationParams& p,
                              const std::string& rawlog_path, int max_frames = 0);

/// Sidecar paths for a rawlog written by simulateRun.
std::string groundTruthPosesPath(const std::string& rawlog_path);
std::string truthMapPath(const std::string& rawlog_path);  ///< the .yaml; read with io::readRosMap

/// Writes a truth raster as ROS map_server files (io::writeRosMap: 0 non-traversable,
/// 254 traversable, 205 unknown; row 0 is the top, max y).
void writeTruthMap(const sim::TruthRaster& truth, const std::string& yaml_path);

}  // namespace upd::mrpt_bridge
