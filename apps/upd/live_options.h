// The command line of `upd live`, in one struct: a new option is a field here and one line in
// parseLiveOptions (live_options.cpp).
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

namespace upd::app {

struct LiveOptions {
  std::string config_path, nav_path;
  // The source: at most one of oni, sensors, kinect; none = the first OpenNI2 device.
  std::string oni;             ///< an OpenNI2 recording
  std::string sensors;         ///< an MRPT sensor file (rawlog-grabber's format)
  std::string sensor_section;  ///< its section (empty: the only one with a driver)
  std::optional<int> kinect;   ///< a Kinect v1 through libfreenect, by index
  int max_frames = 0;          ///< 0: no limit
  std::optional<Eigen::Vector2d> goal;
  std::optional<std::string> out;
  std::optional<std::string> record;  ///< write the observations to this rawlog
  /// The source counts as stopped when no new frame (a new device stamp) came for this long [s].
  double stale_timeout_s = 1.0;
  bool view = false;
  std::optional<std::string> screenshot;  ///< with view: the last view to this PNG
  std::optional<std::string> mount;  ///< --mount FILE.ini: [CameraMountParams] over the nav config's
  bool auto_mount = false;           ///< measure the mount from the floor in the first frames
  std::string base = "sim";  ///< the base driven: sim or ros (live_base.h)
};

/// Throws UsageError naming the option and value.
LiveOptions parseLiveOptions(const std::vector<std::string>& argv);

}  // namespace upd::app
