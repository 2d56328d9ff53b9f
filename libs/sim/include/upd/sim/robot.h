// The simulated robot: its body (the Dune by default) and the depth camera mounted on it, each
// one parameter struct used by `upd simulate`, `upd navigate` and the tests, with the functions
// that place them: the body resting on the terrain and the camera on the body.
//
// Frames: world z up; robot x forward, y left, z up, origin at the footprint centre on the
// ground; camera-optical x right, y down, z forward (render.h). A planar pose is
// (x [m], y [m], yaw [rad]), yaw the heading of the robot's x from the world's x, as
// WorldSpec::start_xy_yaw. The body pose on the terrain lifts a planar pose: z from the mean
// height under the four wheel contacts, pitch and roll from their differences (front - rear
// over the wheelbase, left - right over the track), so the camera tilts with the robot on a
// ramp.
#pragma once

#include "upd/core/camera.h"
#include "upd/core/params.h"
#include "upd/core/point_cloud.h"
#include "upd/sim/render.h"
#include "upd/sim/terrain.h"

#include <Eigen/Geometry>

#include <cstdint>

namespace upd::sim {

/// The physical robot (the Dune by default). Loaded from [RobotBodyParams].
struct RobotBodyParams {
  double length_m = 0.7;     ///< footprint along x [m]
  double width_m = 0.45;     ///< footprint along y [m]
  double wheelbase_m = 0.5;  ///< front to rear wheel contact [m]
  double track_m = 0.4;      ///< left to right wheel contact [m]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("length_m", length_m, "footprint length along the robot's x [m]");
    v("width_m", width_m, "footprint width along the robot's y [m]");
    v("wheelbase_m", wheelbase_m, "distance between front and rear wheel contacts [m]");
    v("track_m", track_m, "distance between left and right wheel contacts [m]");
  }
};

/// The depth camera on the robot (a Kinect by default). Loaded from [CameraMountParams].
struct CameraMountParams {
  double forward_m = 0.3;               ///< optical centre ahead of the robot origin [m]
  double left_m = 0.0;                  ///< ... to its left [m]
  double height_m = 0.5;                ///< ... above the ground [m]
  double pitch_rad = 22.0 * core::kDegToRad;  ///< optical axis pitched down from the robot's x [rad]
  double roll_rad = 0.0;  ///< about the optical axis, the camera's left side up > 0 [rad]
  /// The simulated image is the Kinect's 640 x 480 (fx = fy = 525) divided by this: 4 gives
  /// 160 x 120, enough for the navigation loop at a fraction of the cost.
  int image_downscale = 1;

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("forward_m", forward_m, "camera ahead of the robot origin [m]");
    v("left_m", left_m, "camera left of the robot origin [m]");
    v("height_m", height_m, "camera above the ground [m]");
    v.angleDeg("pitch_deg", pitch_rad, "optical axis pitched down from the robot's x [deg]");
    v.angleDeg("roll_deg", roll_rad, "about the optical axis, the camera's left side up > 0 [deg]");
    v("image_downscale", image_downscale,
      "simulated image = Kinect 640 x 480 divided by this (1, 2, 4 or 8)");
  }
};

/// pose_robot_camera: camera-optical frame to robot frame.
Eigen::Isometry3d cameraOnRobot(const CameraMountParams& mount);
/// pose_robot_mount: the mount's frame (x along the optical axis, y left, z up: the camera's
/// body frame, MRPT's convention for a 3D range sensor's pose) to robot frame. cameraOnRobot
/// is this followed by opticalInMount().
Eigen::Isometry3d mountOnRobot(const CameraMountParams& mount);
/// The camera-optical axes in the mount frame: p_mount = opticalInMount() * p_optical
/// (x_mount = z_optical, y_mount = -x_optical, z_mount = -y_optical).
Eigen::Matrix3d opticalInMount();
/// The simulated camera's intrinsics (the Kinect's scaled by image_downscale).
core::CameraIntrinsics simulatedIntrinsics(const CameraMountParams& mount);

/// pose_world_robot in 3D: the planar pose xy_yaw resting on the terrain (header comment).
Eigen::Isometry3d bodyPoseOnTerrain(const Terrain& terrain, const Eigen::Vector3d& xy_yaw,
                                    const RobotBodyParams& body);
/// pose_world_robot in 3D on flat ground at z = 0 (live mode without terrain knowledge).
Eigen::Isometry3d bodyPoseFlat(const Eigen::Vector3d& xy_yaw);

/// What the camera sees from the body pose: a cloud in the world frame with its sensor origin
/// at the camera (rendered with simulatedIntrinsics and noise, seeded by seed).
core::PointCloud renderCameraWorld(const Terrain& terrain, const Eigen::Isometry3d& pose_world_body,
                             const CameraMountParams& mount, const DepthNoise& noise,
                             std::uint32_t seed);

}  // namespace upd::sim
