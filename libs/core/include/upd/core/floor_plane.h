// The floor under a depth camera: the plane found in clouds in the camera's own frame, and the
// camera mount (height above it, pitch, roll) that plane implies. This is how a camera is
// calibrated on the robot (`upd calibrate-mount`, `upd live --auto-mount`): with the robot on a
// level floor and the floor in view, the floor plane fixes every degree of freedom of the mount
// but the yaw and the horizontal offsets.
//
// Method: RANSAC over the points below the camera (below its horizontal plane by the prior
// up direction), each hypothesis a plane through three points whose normal is within
// max_tilt_rad of the prior up and which passes min_height_m..max_height_m below the camera;
// the plane with the most inliers (distance <= inlier_distance_m) wins. It is then refitted by
// least squares (the smallest-eigenvalue direction of the inliers' covariance), with the
// inliers taken again from every point, twice. Half the hypotheses take their second and third
// points near the first in the cloud's order (image neighbours for an organized cloud), so a
// floor that holds only a few % of the points is still sampled. A floor is large: its inliers
// spread over min_area_m2 at least (a shelf is not a floor). The floor is the lowest surface in view: a
// hypothesis scores its inliers minus the points under it (more than 3 x inlier_distance_m),
// so a table top loses to the floor under it, and a plane with many points under it
// (max_below_ratio) is no floor. Random sampling uses a fixed seed: the same
// input gives the same result.
//
// Frames: the clouds are in the camera-optical frame (x right, y down, z forward). The plane
// is n . p + d = 0 with n the unit up normal (pointing from the floor to the camera) and
// d = the camera's height above the floor [m]. The mount follows upd::sim's
// CameraMountParams: pitch > 0 looks down, roll > 0 raises the camera's left side (a rotation
// about the optical axis); for those angles the up normal in the optical frame is
//   n = (-cos(pitch) sin(roll), -cos(pitch) cos(roll), -sin(pitch)).
#pragma once

#include "upd/core/params.h"
#include "upd/core/point_cloud.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace upd::core {

/// How the floor is searched for. Loaded from [FloorPlaneParams].
struct FloorPlaneParams {
  int ransac_iterations = 500;           ///< plane hypotheses tried
  double inlier_distance_m = 0.03;       ///< a point this close to the plane is on it [m]
  double max_tilt_rad = 45.0 * kDegToRad;  ///< floor normal within this of the prior up [rad]
  double min_height_m = 0.05;            ///< the camera is at least this high [m]
  double max_height_m = 3.0;             ///< ... and at most this [m]
  double min_inlier_share = 0.02;        ///< fewer points on the plane: no floor found
  int min_inliers = 500;                 ///< ... and at least this many points on it
  /// Points more than 3 x inlier_distance_m under the plane, over the points on it: at most
  /// this, else the plane is not the floor (a table top, a slice through clutter).
  double max_below_ratio = 0.25;
  double min_area_m2 = 1.0;              ///< the floor's inliers cover at least this [m^2]
  int max_sample_points = 50000;         ///< RANSAC scores on at most this many points
  int seed = 1;                          ///< random sampling seed

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("ransac_iterations", ransac_iterations, "plane hypotheses tried by RANSAC");
    v("inlier_distance_m", inlier_distance_m, "a point this close to the plane is on it [m]");
    v.angleDeg("max_tilt_deg", max_tilt_rad,
               "the floor normal is within this of the prior up (camera pitch/roll bound) [deg]");
    v("min_height_m", min_height_m, "the camera is at least this high above the floor [m]");
    v("max_height_m", max_height_m, "the camera is at most this high above the floor [m]");
    v("min_inlier_share", min_inlier_share,
      "share of the valid points that must lie on the floor, else no floor is found");
    v("min_inliers", min_inliers, "points that must lie on the floor, else no floor is found");
    v("max_below_ratio", max_below_ratio,
      "points > 3 x inlier_distance_m under the plane over those on it (the floor is lowest)");
    v("min_area_m2", min_area_m2,
      "the points on the floor cover at least this (12 sigma1 sigma2 of their spread) [m^2]");
    v("max_sample_points", max_sample_points, "RANSAC scores hypotheses on this many points");
    v("seed", seed, "random sampling seed (the same input gives the same plane)");
  }
};

/// The floor found (or not) in the camera frame.
struct FloorPlane {
  bool found = false;
  std::string failure;                           ///< why not, when !found
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  ///< unit, up (towards the camera)
  double offset_m = 0;             ///< d in n . p + d = 0: the camera's height [m]
  double rms_residual_m = 0;       ///< RMS distance of the inliers to the plane [m]
  std::size_t inliers = 0;         ///< points on the plane
  std::size_t valid_points = 0;    ///< finite points considered
  std::size_t below = 0;           ///< points more than 3 x the inlier distance under it
  double area_m2 = 0;              ///< the inliers' extent: 12 sigma1 sigma2 in the plane [m^2]
  double inlierShare() const {
    return valid_points ? static_cast<double>(inliers) / valid_points : 0.0;
  }
};

/// The mount a floor implies (header comment for the conventions).
struct MountPose {
  double height_m = 0;   ///< camera above the floor [m]
  double pitch_rad = 0;  ///< optical axis below the horizontal [rad]
  double roll_rad = 0;   ///< about the optical axis, left side up > 0 [rad]
};

/// Finds the floor in the clouds (all in the same camera-optical frame: a static camera's
/// first frames). up_prior: roughly up in that frame (a level camera: (0, -1, 0)). Never
/// throws for a cloud without a floor (found = false and failure says why); throws
/// std::invalid_argument for bad params.
FloorPlane fitFloorPlane(const std::vector<const PointCloud*>& clouds_in_camera,
                         const FloorPlaneParams& params,
                         const Eigen::Vector3d& up_prior = Eigen::Vector3d(0, -1, 0));

/// The mount of a camera above plane (plane.found must hold).
MountPose mountFromFloor(const FloorPlane& plane);

/// The up normal in the camera-optical frame of a camera mounted at pitch and roll.
Eigen::Vector3d floorNormalInCamera(double pitch_rad, double roll_rad);

}  // namespace upd::core
