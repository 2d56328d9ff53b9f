// The ROS map_server map format, the one writer and reader of the project: a trinary 8-bit P5
// PGM (0 = occupied / non-traversable, 254 = free / traversable, 205 = unknown; image row 0 is
// the top, max y) and a YAML beside it with image (the PGM's file name, relative), resolution,
// origin [x_min, y_min, 0.0] (the lower-left corner of the lower-left pixel), negate 0,
// occupied_thresh 0.65, free_thresh 0.196 and mode trinary. The fused traversability grid
// (maps::writeRosMap) and the ground truth of a simulated run are written through here.
//
// The graded cost map (writeRosScaleMap, mode scale) has the same YAML keys with mode: scale
// and grey levels 255 * (1 - p) from each cell's probability of being occupied, which
// map_server reads back as p (0..100 cost between free_thresh and occupied_thresh). A PGM has
// no alpha channel, so an unknown cell is written as the prior p = 0.5 (grey 128): map_server
// gives it cost 66, MRPT's occupancy grid reads it as its own "unknown" 0.5.
#pragma once

#include "upd/core/point_cloud.h"

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace upd::io {

/// Values of the trinary PGM.
inline constexpr std::uint8_t kRosOccupied = 0;
inline constexpr std::uint8_t kRosFree = 254;
inline constexpr std::uint8_t kRosUnknown = 205;

/// The PGM value of a label, and back (as map_server reads a trinary map: < 100 occupied,
/// > 250 free, unknown in between).
std::uint8_t rosPixelOf(core::Label label);
core::Label labelOfRosPixel(std::uint8_t value);

/// A map as the files hold it. Cells are indexed (ix, iy) from the lower-left corner, as the
/// project's grids are; the PGM's row order is the writer's and reader's business.
struct RosMap {
  double resolution_m = 0.05;                           ///< cell side [m/cell]
  Eigen::Vector2d origin_xy = Eigen::Vector2d::Zero();  ///< lower-left corner (world) [m]
  int width = 0, height = 0;                            ///< [cells]
  std::vector<core::Label> labels;  ///< width * height, row-major from the bottom row (iy = 0)

  core::Label at(int ix, int iy) const { return labels[static_cast<std::size_t>(iy) * width + ix]; }
  /// The label of the cell holding a world position; Unknown outside the map.
  core::Label labelAt(double x, double y) const;
};

/// Writes yaml_path and the PGM beside it (same stem, ".pgm"), each atomically (the PGM first).
/// Throws std::invalid_argument for a map whose label count is not width * height or whose
/// resolution is not > 0, std::runtime_error naming the file when writing fails.
void writeRosMap(const RosMap& map, const std::string& yaml_path);

/// A graded map: per cell the probability of being occupied (non-traversable), NaN unknown.
struct RosScaleMap {
  double resolution_m = 0.05;                           ///< cell side [m/cell]
  Eigen::Vector2d origin_xy = Eigen::Vector2d::Zero();  ///< lower-left corner (world) [m]
  int width = 0, height = 0;                            ///< [cells]
  std::vector<float> p_occupied;  ///< width * height, row-major from the bottom row (iy = 0)
};

/// The scale-mode grey level of a probability: round(255 * (1 - p)); NaN (unknown) -> 128.
std::uint8_t rosScalePixelOf(float p_occupied);

/// Writes yaml_path (mode: scale) and the PGM beside it, as writeRosMap does.
void writeRosScaleMap(const RosScaleMap& map, const std::string& yaml_path);

/// Reads a map written by writeRosMap (or by ROS's map_saver in trinary mode: image,
/// resolution and origin are read; other keys are ignored). Throws std::runtime_error naming
/// the file when it cannot be opened, has no image key or its PGM is not an 8-bit P5 image.
RosMap readRosMap(const std::string& yaml_path);

}  // namespace upd::io
