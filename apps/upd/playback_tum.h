// `upd playback DIR` of a TUM RGB-D folder: depth.txt lists `timestamp depth/TIMESTAMP.png`
// (16-bit PNGs, 5000 units per metre), groundtruth.txt the camera's poses
// (`timestamp tx ty tz qx qy qz qw`, the optical frame's pose in a z-up world). The folder is
// turned into DIR_OUT/sequence.rawlog (one CObservation3DRangeScan per depth image, stamped,
// the camera's optical frame as the robot frame) and played back with the ground truth as the
// poses (`--poses`, interpolated at each frame's timestamp), so every playback option and export
// applies. Intrinsics: `--intrinsics CALIB.yaml`, `--tum-camera freiburg1|2|3|ros`, or the
// freiburgN in the folder's name (rgbd_dataset_freiburg1_xyz).
#pragma once

#include <string>
#include <vector>

namespace upd::app {

/// True when the command line's first argument is a directory (a TUM folder).
bool isTumPlayback(const std::vector<std::string>& argv);

/// Converts the folder and plays it back (runPlayback on the rawlog, with --poses). Throws
/// naming the file and field for a missing depth.txt, a bad line, a listed PNG missing, an
/// 8-bit PNG, or a calibration without a focal length.
int runTumPlayback(const std::vector<std::string>& argv);

}  // namespace upd::app
