// The sources of `upd live`: one interface over every route a live frame can come by, each
// yielding MRPT observations with their timestamps, which the live loop scores exactly as
// `upd playback` scores a rawlog's (observation -> cloud in the robot frame, observation_cloud.h).
//
// Routes (docs/SENSORS.md):
//  - OpenNI2 (`upd live`, `--oni FILE.oni`): PrimeSense PS1080 devices (Xtion, Carmine) and
//    .oni recordings; Debian's OpenNI2 has no Kinect v1 driver.
//  - libfreenect (`--kinect [INDEX]`): the Kinect v1 (and fakenect's recordings).
//  - an MRPT sensor file (`--sensors FILE.ini [--sensor-section NAME]`): any sensor MRPT's
//    hwdrivers drive (stereo cameras, Velodyne, OpenNI2 through COpenNI2Sensor, image folders,
//    rawlogs, ...).
// Depth cameras (the first two) become CObservation3DRangeScan in millimetres with the depth
// camera's intrinsics and the [CameraMountParams] mount as the sensor pose, decimated by its
// image_downscale; a sensor file's observations keep the pose of their section (pose_x ...).
#pragma once

#include "upd/core/camera.h"

#include <Eigen/Geometry>

#include <limits>
#include <memory>
#include <string>

namespace mrpt::obs {
class CObservation;
}

namespace upd::app {

struct LiveOptions;

/// One observation of a live source.
struct LiveFrame {
  std::shared_ptr<mrpt::obs::CObservation> observation;
  /// The device's own time of the frame [s]: two frames with the same stamp are the same frame
  /// delivered twice (stale). NaN when the device gives none.
  double stamp_s = std::numeric_limits<double>::quiet_NaN();
};

enum class Poll {
  Frame,    ///< frame holds a new observation
  Nothing,  ///< none arrived within the source's short wait (~0.1 s); poll again
  End,      ///< the end of a recording
};

class LiveSource {
 public:
  virtual ~LiveSource() = default;
  /// Throws std::runtime_error (one line) when the device fails.
  virtual Poll poll(LiveFrame& frame) = 0;
  /// What is read: "PrimeSense Carmine 1.09 (1d27:0601)", "sensors.ini [CAMERA] CCameraSensor".
  virtual std::string description() const = 0;
};

/// The source the options name. Throws std::runtime_error (one line) when it cannot be opened.
std::unique_ptr<LiveSource> openLiveSource(const LiveOptions& options,
                                           const Eigen::Isometry3d& mount_on_robot,
                                           int image_downscale);

/// A depth image (z-depth [m], 0 or NaN invalid) as an MRPT 3D range scan: range image in
/// millimetres, every downscale-th pixel of every downscale-th row with the intrinsics scaled to
/// match, sensorPose = mount_on_robot (MRPT's range-sensor frame: x forward, y left, z up),
/// stamped now.
std::shared_ptr<mrpt::obs::CObservation> depthObservation(const core::DepthImage& depth,
                                                          const core::CameraIntrinsics& K,
                                                          const Eigen::Isometry3d& mount_on_robot,
                                                          int downscale, const std::string& label);

#ifdef UPD_HAVE_OPENNI2
std::unique_ptr<LiveSource> openOpenNI2Source(const std::string& oni,
                                              const Eigen::Isometry3d& mount_on_robot,
                                              int image_downscale);
#endif
#ifdef UPD_HAVE_FREENECT
std::unique_ptr<LiveSource> openFreenectSource(int index, const Eigen::Isometry3d& mount_on_robot,
                                               int image_downscale);
#endif

}  // namespace upd::app
