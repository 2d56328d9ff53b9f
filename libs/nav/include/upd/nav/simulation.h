// The simulated world around the navigation loop: the robot's body resting on the terrain, the
// depth camera on it, and the ground-truth checks (collisions and clearance).
//
// Frames: world z up; robot x forward, y left, z up, origin at the footprint centre on the
// ground; camera-optical x right, y down, z forward (render.h). The body pose is the 2D pose of
// the kinematic simulator lifted onto the terrain: z from the mean height under the four wheels,
// pitch and roll from their differences (front-rear over the wheelbase, left-right over the
// track), so the camera tilts with the robot on the ramp.
#pragma once

#include "upd/core/camera.h"
#include "upd/core/params.h"
#include "upd/core/point_cloud.h"
#include "upd/core/render.h"
#include "upd/core/terrain.h"
#include "upd/nav/robot_base.h"

#include <Eigen/Geometry>

#include <cstdint>
#include <vector>

namespace upd::nav {

/// The physical robot (Dune by default). Loaded from [RobotBodyParams].
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

/// The depth camera on the robot. Loaded from [CameraMountParams].
struct CameraMountParams {
  double forward_m = 0.3;               ///< optical centre ahead of the robot origin [m]
  double left_m = 0.0;                  ///< ... to its left [m]
  double height_m = 0.5;                ///< ... above the ground [m]
  double pitch_rad = 22.0 * kDegToRad;  ///< optical axis pitched down from the robot's x [rad]
  /// The simulated image is the Kinect's 640 x 480 (fx = fy = 525) divided by this: 4 gives
  /// 160 x 120, enough for the loop at a fraction of the cost.
  int image_downscale = 4;

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("forward_m", forward_m, "camera ahead of the robot origin [m]");
    v("left_m", left_m, "camera left of the robot origin [m]");
    v("height_m", height_m, "camera above the ground [m]");
    v.angleDeg("pitch_deg", pitch_rad, "optical axis pitched down from the robot's x [deg]");
    v("image_downscale", image_downscale,
      "simulated image = Kinect 640 x 480 divided by this (1, 2, 4 or 8)");
  }
};

/// pose_robot_camera: camera-optical frame to robot frame.
Eigen::Isometry3d cameraOnRobot(const CameraMountParams& mount);
/// The simulated camera's intrinsics (Kinect scaled by image_downscale).
CameraIntrinsics simulatedIntrinsics(const CameraMountParams& mount);
/// pose_world_robot in 3D: the planar pose resting on the terrain (see the header comment).
Eigen::Isometry3d bodyPoseOnTerrain(const Terrain& terrain, const Pose2D& pose_world_robot,
                                    const RobotBodyParams& body);
/// pose_world_robot in 3D for flat ground at z = 0 (live mode without terrain knowledge).
Eigen::Isometry3d bodyPoseFlat(const Pose2D& pose_world_robot);

/// Renders what the camera sees from the body pose, as a cloud in the world frame with its
/// sensor origin at the camera.
PointCloud renderCameraWorld(const Terrain& terrain, const Eigen::Isometry3d& pose_world_body,
                             const CameraMountParams& mount, const DepthNoise& noise,
                             std::uint32_t seed);

/// The ground truth rasterised every cell_m over the terrain's extent, for the checks of a run.
/// A footprint collides when a NonTraversable raster cell centre lies inside it; clearance is
/// the distance from the footprint rectangle to the nearest NonTraversable cell centre (0 when
/// colliding), searched up to search_m beyond the footprint (farther: search_m).
class TruthRaster {
 public:
  TruthRaster(const Terrain& terrain, double cell_m);

  double cellSize() const { return cell_m_; }
  int sizeX() const { return nx_; }
  int sizeY() const { return ny_; }
  Label at(int ix, int iy) const { return labels_[static_cast<std::size_t>(iy) * nx_ + ix]; }
  Eigen::Vector2d cellCenter(int ix, int iy) const;

  bool collides(const Pose2D& pose_world_robot, const RobotBodyParams& body) const;
  double clearance(const Pose2D& pose_world_robot, const RobotBodyParams& body,
                   double search_m) const;

 private:
  Eigen::Vector2d min_xy_;
  double cell_m_;
  int nx_ = 0, ny_ = 0;
  std::vector<Label> labels_;
};

}  // namespace upd::nav
