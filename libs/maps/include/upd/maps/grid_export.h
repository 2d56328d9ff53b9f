// Writing the traversability grid as images: a colour PNG with a legend for people, and the
// PGM + YAML pairs of ROS map_server for planners (trinary labels, and a graded cost map).
//
// Every file is written atomically (temporary file in the same directory, then renamed); on
// failure a one-line std::runtime_error names the file and no temporary file is left behind.
#pragma once

#include "upd/maps/traversability_grid.h"

#include <array>
#include <cstdint>
#include <string>

namespace upd::maps {

/// Colour of a probability of being non-traversable: green (0) -> yellow (0.5) -> red (1); grey
/// (128, 128, 128) for NaN (unknown). Returned as {r, g, b}.
std::array<std::uint8_t, 3> traversabilityColourRgb(float p_nontrav);
inline constexpr std::array<std::uint8_t, 3> kUnknownColourRgb{128, 128, 128};

/// Where writeColourPng put things: the map occupies rows [0, map_height_px) (north up, row 0 is
/// y max) and columns [0, map_width_px); the legend occupies rows
/// [legend_top_px, image_height_px) over the full width.
struct ColourPngLayout {
  int pixels_per_cell = 1;
  int map_width_px = 0;
  int map_height_px = 0;
  int legend_top_px = 0;
  int image_width_px = 0;
  int image_height_px = 0;
};

/// Writes the grid as a colour PNG (north up) with a legend below it: a colour bar from
/// "traversable" to "non-traversable", an "unknown" swatch, the cell size and a scale bar.
/// pixels_per_cell = 0 picks a scale that makes the map about 600 px wide (1..8 px per cell).
ColourPngLayout writeColourPng(const TraversabilityGrid& grid, const std::string& path,
                               int pixels_per_cell = 0);

/// Writes path_without_ext + ".pgm" and ".yaml" in ROS map_server's format through
/// io::writeRosMap (upd/io/ros_map.h: the PGM values io::kRosOccupied, kRosFree, kRosUnknown),
/// each cell's label from labelOf, so the thresholds of GridParams decide.
void writeRosMap(const TraversabilityGrid& grid, const std::string& path_without_ext);

/// The graded cost map beside it: path_without_ext + ".pgm" and ".yaml" with mode: scale,
/// each cell's grey level from its probability of being non-traversable (probabilityOf;
/// unknown cells as the prior 0.5), through io::writeRosScaleMap.
void writeRosCostMap(const TraversabilityGrid& grid, const std::string& path_without_ext);

}  // namespace upd::maps
