// A simulated robot run recorded as a real MRPT rawlog: the embedded default data of UPD-Nav.
//
// A virtual Dune (0.7 x 0.45 m, wheel diameter 0.2 m, a Kinect at its front about 0.5 m high,
// pitched down) drives through a generated world (terrain.h): from the world's start to its goal
// and back, along a route planned on the ground truth with the robot's clearance. Its body
// follows the terrain (pitch and roll from the wheel contact heights, so it tilts on the ramp).
// Every frame_spacing_m it records a 640 x 480 CObservation3DRangeScan rendered by ray casting
// with Kinect noise (render.h), preceded by a CActionRobotMovement2D odometry increment with
// drift. Beside the rawlog it writes the ground-truth poses (TUM: t x y z qx qy qz qw) and the
// world's ground-truth traversability grid (ROS map_server PGM + YAML).
#pragma once

#include "upd/core/camera.h"
#include "upd/core/params.h"
#include "upd/core/render.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <string>
#include <vector>

namespace upd {
class Terrain;
struct WorldSpec;
}  // namespace upd

namespace upd::mrptbridge {

struct SimulationParams {
  double robot_length_m = 0.7;
  double robot_width_m = 0.45;
  double wheel_diameter_m = 0.2;
  double camera_forward_m = 0.3;   ///< camera ahead of the robot centre [m]
  double camera_height_m = 0.5;    ///< camera above the ground under the robot [m]
  double camera_pitch_rad = 22.0 * kDegToRad;  ///< camera pitched down by this [rad]
  double speed_mps = 0.4;          ///< driving speed, sets the timestamps [m/s]
  double frame_spacing_m = 0.2;    ///< distance driven between frames [m]
  double clearance_m = 0.45;       ///< route keeps this far from non-traversable truth [m]
  double odometry_sigma_ratio = 0.02;  ///< odometry distance noise, fraction of the step [-]
  double odometry_yaw_bias_rad_per_m = 0.5 * kDegToRad;  ///< odometry heading drift [rad/m]
  double truth_cell_m = 0.05;      ///< cell of the ground-truth grid [m]
  int seed = 1;
  bool return_to_start = true;     ///< drive back to the start after the goal

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("robot_length_m", robot_length_m, "robot body length [m]");
    v("robot_width_m", robot_width_m, "robot body width [m]");
    v("wheel_diameter_m", wheel_diameter_m, "wheel diameter [m]");
    v("camera_forward_m", camera_forward_m, "camera ahead of the robot centre [m]");
    v("camera_height_m", camera_height_m, "camera height above the ground [m]");
    v.angleDeg("camera_pitch_deg", camera_pitch_rad, "camera pitched down by [deg]");
    v("speed_mps", speed_mps, "driving speed [m/s]");
    v("frame_spacing_m", frame_spacing_m, "distance between recorded frames [m]");
    v("clearance_m", clearance_m, "route clearance from non-traversable ground truth [m]");
    v("odometry_sigma_ratio", odometry_sigma_ratio, "odometry noise per step, fraction [-]");
    v.angleDeg("odometry_yaw_bias_deg_per_m", odometry_yaw_bias_rad_per_m,
               "odometry heading drift [deg/m]");
    v("truth_cell_m", truth_cell_m, "cell of the ground-truth traversability grid [m]");
    v("seed", seed, "noise seed");
    v("return_to_start", return_to_start, "drive back to the start after reaching the goal");
  }
};

/// The sensor pose on the robot in MRPT's convention for 3D range scans (x forward, y left,
/// z up), as a rigid transform robot <- sensor.
Eigen::Isometry3d kinectPoseOnRobot(const SimulationParams& p);

/// The rigid transform from MRPT's 3D-scan sensor frame to the camera-optical frame's points:
/// p_sensor = kOpticalToSensor * p_optical (x_s = z_o, y_s = -x_o, z_s = -y_o).
Eigen::Matrix3d opticalToMrptSensor();

/// A route through the world, planned on the truth grid: poses every frame_spacing_m with the
/// robot's body resting on the terrain. Throws if the goal cannot be reached (then the route
/// ends at the reachable cell nearest to it only when allow_partial).
struct RoutePose {
  double t_s = 0;
  Eigen::Isometry3d pose_world_robot = Eigen::Isometry3d::Identity();
  double yaw_rad = 0;  ///< heading in the world frame
};
std::vector<RoutePose> planRoute(const WorldSpec& world, const SimulationParams& p);

struct SimulationSummary {
  std::size_t frames = 0;
  double path_length_m = 0;
  double duration_s = 0;
  std::string rawlog_path, poses_path, truth_yaml_path;
};

/// Writes rawlog_path (gzip MRPT rawlog, actions + sensory frames), <stem>.gt.tum and
/// <stem>.truth.pgm/.yaml beside it; every file through a temporary file and a rename.
SimulationSummary simulateRun(const WorldSpec& world, const SimulationParams& p,
                              const std::string& rawlog_path, int max_frames = 0);

/// Sidecar paths for a rawlog written by simulateRun.
std::string groundTruthPosesPath(const std::string& rawlog_path);
std::string truthMapPath(const std::string& rawlog_path);  ///< the .yaml

/// The ground-truth traversability grid of a world, as ROS map_server files (0 = non-traversable,
/// 254 = traversable, 205 = unknown; row 0 is the top, max y).
void writeTruthMap(const Terrain& terrain, double cell_m, const std::string& yaml_path);

/// A ground-truth grid read back from a ROS map_server YAML + PGM.
struct TruthGrid {
  double resolution_m = 0.05;
  Eigen::Vector2d origin_xy = Eigen::Vector2d::Zero();  ///< world position of the lower-left
  int width = 0, height = 0;
  std::vector<std::uint8_t> pgm;  ///< row-major, row 0 = top
  /// Label at a world position (Unknown outside).
  int labelAt(double x, double y) const;  ///< 0 traversable, 1 non-traversable, 2 unknown
};
TruthGrid readTruthMap(const std::string& yaml_path);

}  // namespace upd::mrptbridge
