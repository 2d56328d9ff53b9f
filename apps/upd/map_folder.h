// A map folder: the files `upd playback` writes and `upd map` reads, merges, crops and
// re-writes. The grid comes back from map.tif (every layer, without loss) and the tree from
// map_traversability.ot; summary.json says what run(s) the map came from.
#pragma once

#include "upd/maps/traversability_grid.h"
#include "upd/maps/traversability_octree.h"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace upd::app {

/// Every map file, in the order they are written (summary.json is written last, by the caller).
const std::vector<std::string>& mapFileNames();

/// Writes every map file of mapFileNames() into dir: map.png, the ROS maps (map.pgm/.yaml
/// trinary, map_cost.pgm/.yaml graded), map.tif (GeoTIFF, the CRS of epsg when not 0), the
/// trees (map.ot, map_colour.ot, map_traversability.ot, map.bt) and map.3Dscene with the
/// trajectory. Refreshes the tree's inner nodes first.
void writeMapFiles(const maps::TraversabilityGrid& grid, maps::TraversabilityOcTree& tree,
                   const std::vector<Eigen::Vector3d>& trajectory, const std::filesystem::path& dir,
                   int epsg);

/// The grid's and the tree's statistics as summary.json holds them.
nlohmann::json gridJson(const maps::TraversabilityGrid& grid);
nlohmann::json octreeJson(const maps::TraversabilityOcTree& tree);

/// A map folder read back.
struct MapFolder {
  std::filesystem::path dir;
  maps::TraversabilityGrid grid;
  std::unique_ptr<maps::TraversabilityOcTree> tree;
  int epsg = 0;                 ///< the GeoTIFF's CRS (0: none)
  nlohmann::json summary;       ///< summary.json, or null when absent
};

/// Reads dir/map.tif, dir/map_traversability.ot and dir/summary.json (optional). Throws
/// std::runtime_error naming the file that is missing or unreadable.
MapFolder readMapFolder(const std::filesystem::path& dir);

/// The rawlogs a folder's map came from (summary.json's "rawlogs", else its "rawlog").
std::vector<std::string> sourceRawlogs(const nlohmann::json& summary);

/// Writes the map files and a summary.json (extra holds what the caller adds: merged_from,
/// region, ...; the grid and octree statistics and the output list are added here).
void writeMapFolder(const maps::TraversabilityGrid& grid, maps::TraversabilityOcTree& tree,
                    int epsg, const std::filesystem::path& dir, nlohmann::json extra);

}  // namespace upd::app
