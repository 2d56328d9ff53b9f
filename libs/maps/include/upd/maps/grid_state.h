// The grid's whole state in a file, to continue a run later: the parameters, the window's
// place and every observed cell (the window's and the kept tiles'), bit for bit. Reloaded, the
// grid fuses the next frames exactly as the grid that was saved would have (a test builds a
// map in two halves with a save and a reload between them and compares it with one built in one
// go). Not an exchange format: for other programs export the grid (grid_export.h).
//
// Layout: the line "UPD grid state 1", the [GridParams] keys as "key value" lines, the line
// "window I0 J0" (world index of the window's first cell), the line "tiles N", then N tiles, each
// "tx ty bytes\n" followed by that many bytes of zlib-compressed cell records (grid_tiles.h).
#pragma once

#include "upd/maps/traversability_grid.h"

#include <string>

namespace upd::maps {

/// Writes the grid's state (through a temporary file and a rename). Throws std::runtime_error
/// naming the file when it cannot be written.
void writeGridState(const TraversabilityGrid& grid, const std::string& path);
/// Reads a state written by writeGridState. Throws std::runtime_error naming the file and what
/// is wrong for a missing, truncated or corrupt file.
TraversabilityGrid readGridState(const std::string& path);

}  // namespace upd::maps
