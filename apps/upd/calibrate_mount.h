// The camera mount measured from the floor, for the `upd` commands: `upd calibrate-mount`
// (frames from a file), `upd live --auto-mount` (the first frames of the camera) and the
// `--mount FILE.ini` option of `upd live` (a mount written by calibrate-mount). The method is
// in upd/core/floor_plane.h and upd/sim/mount_calibration.h.
#pragma once

#include "upd/core/point_cloud.h"
#include "upd/sim/robot.h"

#include <functional>
#include <string>

namespace mrpt::obs {
class CObservation;
}

namespace upd::app {

/// Frames `upd live --auto-mount` calibrates on.
constexpr int kAutoMountFrames = 5;

/// Reads up to frames clouds in the camera-optical frame from next_cloud (false: no more),
/// finds the floor, prints the calibration's summary line and returns the calibrated mount.
/// Throws std::runtime_error ("no floor found in N frames: ...; not navigating ...") when there
/// is no floor: a run must not start on an unknown mount.
sim::CameraMountParams autoMount(const std::function<bool(core::PointCloud&)>& next_cloud,
                                 const sim::CameraMountParams& configured, int frames);

/// The cloud of a recorded or live observation (a range image, a stereo pair, a point cloud)
/// moved back from the robot frame to its camera's optical frame, the frame whose mount is
/// calibrated; optical_on_robot (when given) receives the recorded optical frame on the robot.
/// False when the observation gives no finite point.
bool opticalFrameCloud(const mrpt::obs::CObservation& obs, core::PointCloud& cloud,
                       Eigen::Isometry3d* optical_on_robot = nullptr);

/// Reads [CameraMountParams] from mount_ini (as `upd calibrate-mount --output` writes it) over
/// mount, strictly: another section or key in the file is an error naming it.
void loadMountFile(const std::string& mount_ini, sim::CameraMountParams& mount);

/// Puts a recorded camera observation on mount (`upd playback --mount`): a 3D range scan's
/// sensor pose becomes the mount's frame (sim::mountOnRobot), a stereo pair's the optical frame
/// (sim::cameraOnRobot). Other observations are left as recorded.
void remount(mrpt::obs::CObservation& obs, const sim::CameraMountParams& mount);

}  // namespace upd::app
