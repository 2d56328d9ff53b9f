// `upd playback RUN.bag`: a ROS 1 bag enters the rawlog pipeline. Its depth frames (Image +
// CameraInfo) become CObservation3DRangeScan and its PointCloud2 frames CObservationPointCloud,
// each with its sensor pose on base_link from the bag's tf, in DIR/bag.rawlog; the robot poses
// (map or odom -> base_link) go to DIR/bag_poses.tum, which playback then uses as --poses.
// Built with ROS 1 (UPD_HAVE_ROS1); without it a .bag is refused with one line.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace upd::app {

/// What a bag became.
struct BagInput {
  std::string rawlog;                ///< the observations
  std::optional<std::string> poses;  ///< TUM robot poses; empty when the bag's tf has none
  std::string summary;               ///< one line: frames, topics, skipped messages
};

/// Nothing for a path that is not a .bag; otherwise the converted files in out_dir (created).
/// Throws std::runtime_error naming the bag when it cannot be read or holds no frame.
std::optional<BagInput> convertBagInput(const std::string& path,
                                        const std::filesystem::path& out_dir);

}  // namespace upd::app
