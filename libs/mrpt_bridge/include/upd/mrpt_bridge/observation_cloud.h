// MRPT observations to point clouds in the ROBOT frame (x forward, y left, z up).
//
// Every supported observation becomes a upd::PointCloud in the robot frame: its points were
// measured in the sensor frame and moved by the observation's sensor pose on the robot, and the
// cloud's sensor_origin is the sensor's position on the robot (range cut-off and normal
// orientation use it). Image-like sensors keep their layout (organized, NaN where invalid):
//  - CObservation3DRangeScan: range image + depth camera intrinsics (with distortion, through
//    MRPT's own unprojection look-up table, so the points are exactly those of unprojectInto),
//    range_is_depth honoured, externally stored images loaded; pixel (u, v) -> point
//    v * width + u, range 0 -> NaN. The MRPT sensor frame of 3D range scans is x forward
//    (depth), y left, z up. A scan that holds only points3D gives an unorganized cloud.
//  - CObservationPointCloud: its point map (unorganized), externally stored maps loaded.
//  - CObservationVelodyneScan: raw packets decoded by generatePointCloud() with the scan's
//    calibration (the model's default one when the scan carries none); unorganized.
//  - CObservationRotatingScan: organized rings x firings; MRPT 2.5 stores no per-ring
//    elevation, so the model's default Velodyne calibration gives it (VLP-16, HDL-32, HDL-64).
//    Column c is at azimuth startAzimuth + azimuthSpan * c / (columnCount - 1), counter-
//    clockwise, as the class documents. (MRPT 2.5.8's own fromVelodyne() sizes the matrix for
//    32 firings per block and fills only the first 1/16 of the columns of a VLP-16 sweep; such
//    scans come out squeezed in azimuth: convert the CObservationVelodyneScan instead.)
//  - CObservationStereoImages: OpenCV StereoSGBM on the pair (rectified first with OpenCV when
//    the left camera has distortion), calibration from the observation or from SourceParams;
//    organized in the left camera-optical frame, then moved by the camera pose (MRPT camera
//    poses are optical frames: x right, y down, z forward).
// Anything else (2D laser scans, odometry, images without a pair, ...) gives an empty cloud and
// a reason, which the caller counts.
#pragma once

#include "upd/core/point_cloud.h"
#include "upd/mrpt_bridge/stereo.h"

#include <Eigen/Geometry>

#include <string>

namespace mrpt::obs {
class CObservation;
}

namespace upd::mrpt_bridge {

/// How observations become clouds. Read from the ini section [SourceParams]; the stereo
/// matcher from [StereoMatchParams].
struct SourceParams {
  bool color_enabled = true;         ///< colour points from the intensity / left image
  double lidar_min_range_m = 1.0;    ///< LiDAR returns nearer than this are dropped [m]
  double lidar_max_range_m = 200.0;  ///< LiDAR returns farther than this are dropped [m]
  /// Stereo calibration of the rectified left camera, used instead of the observation's when
  /// stereo_fx_px > 0 (then fy, cx, cy and the baseline must be set too).
  double stereo_fx_px = 0, stereo_fy_px = 0, stereo_cx_px = 0, stereo_cy_px = 0;
  double stereo_baseline_m = 0;  ///< [m]
  StereoMatchParams stereo;      ///< [StereoMatchParams], not a key of [SourceParams]

  bool hasStereoCalibration() const { return stereo_fx_px > 0; }
  void validate() const;
  template <class V>
  void visit(V& v) {
    v("color_enabled", color_enabled, "colour points from the intensity or left image");
    v("lidar_min_range_m", lidar_min_range_m, "LiDAR returns nearer than this are dropped [m]");
    v("lidar_max_range_m", lidar_max_range_m, "LiDAR returns farther than this are dropped [m]");
    v("stereo_fx_px", stereo_fx_px, "stereo calibration override (0 = from the observation) [px]");
    v("stereo_fy_px", stereo_fy_px, "stereo calibration override [px]");
    v("stereo_cx_px", stereo_cx_px, "stereo calibration override [px]");
    v("stereo_cy_px", stereo_cy_px, "stereo calibration override [px]");
    v("stereo_baseline_m", stereo_baseline_m, "stereo baseline override [m]");
  }
};

/// A converted observation.
struct ObservationCloud {
  /// Robot frame, metres; organized for image-like sensors. sensor_origin = the sensor's
  /// position on the robot.
  core::PointCloud cloud_in_robot;
  /// Pose of the sensor frame in the robot frame (for stereo: of the left optical frame).
  Eigen::Isometry3d sensor_pose_on_robot = Eigen::Isometry3d::Identity();
  std::string source_class;    ///< short MRPT class name, e.g. "CObservation3DRangeScan"
  std::string skipped_reason;  ///< non-empty: no cloud, and why

  bool ok() const { return skipped_reason.empty(); }
  bool organized() const { return cloud_in_robot.isOrganized(); }
};

/// Converts one observation (see the header comment). Never throws for an unsupported type or
/// a missing external file (skipped_reason says why); throws std::invalid_argument for bad
/// params.
ObservationCloud toCloud(const mrpt::obs::CObservation& obs, const SourceParams& params = {});

/// The same into out, reusing its cloud's buffers (a sensor loop converts a range image
/// without allocating once warm).
void toCloud(const mrpt::obs::CObservation& obs, const SourceParams& params, ObservationCloud& out);

}  // namespace upd::mrpt_bridge
