// `upd map merge` and `upd map crop`: map folders fused or cut, and written again whole.
#include "cli.h"
#include "cmd_map.h"
#include "map_folder.h"
#include "run_config.h"

#include "upd/maps/map_merge.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

namespace upd::app {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// Maps of another frame cannot be merged: one line naming both folders and what differs.
void requireSameFrame(const MapFolder& a, const MapFolder& b) {
  auto refuse = [&](const std::string& what) {
    throw std::runtime_error(b.dir.string() + " is not in the frame of " + a.dir.string() + ": " +
                             what + "; maps of different frames cannot be merged");
  };
  auto differ = [](double x, double y) { return std::abs(x - y) > 1e-9 * std::max(x, y); };
  if (differ(a.grid.cellSize(), b.grid.cellSize())) {
    refuse("cell size " + std::to_string(b.grid.cellSize()) + " m, not " +
           std::to_string(a.grid.cellSize()) + " m");
  }
  if (differ(a.tree->getResolution(), b.tree->getResolution())) {
    refuse("voxel size " + std::to_string(b.tree->getResolution()) + " m, not " +
           std::to_string(a.tree->getResolution()) + " m");
  }
  if (a.epsg != b.epsg) {
    refuse("CRS EPSG:" + std::to_string(b.epsg) + ", not EPSG:" + std::to_string(a.epsg) +
           " (0: none)");
  }
}

maps::Region parseRegion(const std::string& text) {
  std::istringstream in(text);
  double v[4];
  char comma = 0;
  for (int k = 0; k < 4; ++k) {
    if (!(in >> v[k]) || (k < 3 && !(in >> comma && comma == ','))) {
      throw UsageError("option --region = '" + text + "': expected XMIN,YMIN,XMAX,YMAX [m]");
    }
  }
  if (in >> comma) throw UsageError("option --region = '" + text + "': expected four numbers");
  if (!(v[2] > v[0] && v[3] > v[1])) {
    throw UsageError("option --region = '" + text + "': needs XMAX > XMIN and YMAX > YMIN");
  }
  return {v[0], v[1], v[2], v[3]};
}

}  // namespace

int runMapMerge(const std::vector<std::string>& argv) {
  const Args args(argv, {"--output", "--config"}, {});
  if (args.positionals().size() < 2) throw UsageError("map merge takes two or more DIRs");
  if (!args.has("--output")) throw UsageError("--output DIR is required");
  const maps::FusionParams fusion =
      args.has("--config") ? loadRunConfig(*args.str("--config")).fusion : maps::FusionParams{};
  std::vector<MapFolder> in;
  for (const auto& dir : args.positionals()) {
    in.push_back(readMapFolder(dir));
    requireSameFrame(in.front(), in.back());
  }
  maps::TraversabilityGrid grid = in.front().grid;
  for (std::size_t k = 1; k < in.size(); ++k) grid = maps::windowCovering(grid, in[k].grid);
  json extra;
  extra["merged_from"] = json::array();
  extra["rawlogs"] = json::array();
  for (const MapFolder& m : in) {
    maps::mergeGridInto(grid, m.grid, fusion);  // the window covers every input: none dropped
    if (&m != &in.front()) maps::mergeOctreeInto(*in.front().tree, *m.tree, fusion);
    extra["merged_from"].push_back(fs::absolute(m.dir).lexically_normal().string());
    for (const auto& r : sourceRawlogs(m.summary)) {
      if (std::find(extra["rawlogs"].begin(), extra["rawlogs"].end(), r) == extra["rawlogs"].end()) {
        extra["rawlogs"].push_back(r);
      }
    }
  }
  const fs::path out = *args.str("--output");
  writeMapFolder(grid, *in.front().tree, in.front().epsg, out, extra);
  const maps::GridStats gs = maps::computeStats(grid);
  std::printf("merged %zu maps: %zu known cells, %zu non-traversable -> %s\n", in.size(), gs.known,
              gs.non_traversable, out.string().c_str());
  return 0;
}

int runMapCrop(const std::vector<std::string>& argv) {
  const Args args(argv, {"--output", "--region"}, {});
  if (args.positionals().size() != 1) throw UsageError("map crop takes one DIR");
  if (!args.has("--region")) throw UsageError("--region XMIN,YMIN,XMAX,YMAX is required");
  if (!args.has("--output")) throw UsageError("--output DIR is required");
  const maps::Region region = parseRegion(*args.str("--region"));
  MapFolder m = readMapFolder(args.positionals()[0]);
  if (region.x_min >= m.grid.xMax() || region.x_max <= m.grid.xMin() ||
      region.y_min >= m.grid.yMax() || region.y_max <= m.grid.yMin()) {
    throw std::runtime_error("region " + *args.str("--region") + " lies outside the map of " +
                             m.dir.string());
  }
  const maps::TraversabilityGrid grid = maps::cropGrid(m.grid, region);
  maps::cropOctree(*m.tree, region);
  json extra;
  extra["cropped_from"] = fs::absolute(m.dir).lexically_normal().string();
  extra["region"] = {region.x_min, region.y_min, region.x_max, region.y_max};
  extra["rawlogs"] = sourceRawlogs(m.summary);
  const fs::path out = *args.str("--output");
  writeMapFolder(grid, *m.tree, m.epsg, out, extra);
  const maps::GridStats gs = maps::computeStats(grid);
  std::printf("cropped to %s: %zu known cells, %zu non-traversable -> %s\n",
              args.str("--region")->c_str(), gs.known, gs.non_traversable, out.string().c_str());
  return 0;
}

}  // namespace upd::app
