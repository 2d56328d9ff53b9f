// `upd map`: work on exported map folders (what `upd playback` writes): info prints what a
// folder holds, merge fuses folders of the same frame, crop cuts a region. Every command that
// writes re-writes every map file (map_folder.h).
#include "cli.h"
#include "cmd_map.h"
#include "commands.h"
#include "map_folder.h"

#include "upd/gdal/geotiff.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

namespace upd::app {

const char* const kMapUsage =
    "usage: upd map info DIR\n"
    "       upd map merge DIR1 DIR2 [DIR...] --output DIR [--config FILE.ini]\n"
    "       upd map crop DIR --region XMIN,YMIN,XMAX,YMAX --output DIR\n"
    "  Works on map folders written by `upd playback` (map.tif and map_traversability.ot are\n"
    "  read; every map file is written again).\n\n"
    "  info    what the folder holds: extent, known cells (traversable / non-traversable),\n"
    "          memory, the GeoTIFF's bands, the tree, the run(s) it came from, its files\n"
    "  merge   fuses maps of the same frame (same world frame, cell size, voxel size and CRS)\n"
    "          into one: log-odds add (clamped as [FusionParams] says), zeta_min is the\n"
    "          minimum, means are weighted by their point counts; a folder of another cell\n"
    "          size or CRS is refused\n"
    "  crop    the cells and voxels of the region [XMIN, XMAX) x [YMIN, YMAX) [m, map frame]\n\n"
    "options:\n"
    "  --output DIR        output folder, created if missing (merge, crop)\n"
    "  --config FILE.ini   [FusionParams] of the merge (default: the built-in defaults)\n"
    "  --region X0,Y0,X1,Y1  the region to keep [m] (crop)\n";

namespace {

namespace fs = std::filesystem;

void printExtent(const maps::TraversabilityGrid& g) {
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  maps::forEachKnownCell(g, [&](int cx, int cy, const maps::GridCell&) {
    x0 = std::min(x0, g.xMin() + cx * g.cellSize());
    y0 = std::min(y0, g.yMin() + cy * g.cellSize());
    x1 = std::max(x1, g.xMin() + (cx + 1) * g.cellSize());
    y1 = std::max(y1, g.yMin() + (cy + 1) * g.cellSize());
  });
  std::printf("  grid window: %d x %d cells of %.3g m over x [%.2f, %.2f] y [%.2f, %.2f] m\n", g.sizeX(),
              g.sizeY(), g.cellSize(), g.xMin(), g.xMax(), g.yMin(), g.yMax());
  if (x0 <= x1) {
    // The image exports (map.pgm, map_cost.pgm, map.png, map.tif) cover the known area only.
    std::printf("  known area: %d x %d cells, x [%.2f, %.2f] y [%.2f, %.2f] m (the image exports)\n",
                static_cast<int>(std::lround((x1 - x0) / g.cellSize())),
                static_cast<int>(std::lround((y1 - y0) / g.cellSize())), x0, x1, y0, y1);
  }
}

void printSource(const nlohmann::json& s) {
  if (s.is_null()) {
    std::printf("  source: no summary.json\n");
    return;
  }
  for (const auto& r : sourceRawlogs(s)) std::printf("  rawlog: %s\n", r.c_str());
  if (s.contains("config")) std::printf("  config: %s\n", s["config"].get<std::string>().c_str());
  if (s.contains("frames_processed")) {
    std::printf("  frames: %s processed of %s read (poses: %s)\n",
                s["frames_processed"].dump().c_str(), s["frames_read"].dump().c_str(),
                s.value("pose_source", std::string("?")).c_str());
  }
  for (const char* k : {"merged_from", "cropped_from", "region"}) {
    if (s.contains(k)) std::printf("  %s: %s\n", k, s[k].dump().c_str());
  }
}

}  // namespace

int runMapInfo(const std::vector<std::string>& argv) {
  const Args args(argv, {}, {});
  if (args.positionals().size() != 1) throw UsageError("map info takes one DIR");
  const MapFolder m = readMapFolder(args.positionals()[0]);
  const maps::GridStats gs = maps::computeStats(m.grid);
  const maps::OctreeStats os = maps::computeStats(*m.tree);
  std::printf("map folder %s\n", m.dir.string().c_str());
  printSource(m.summary);
  printExtent(m.grid);
  std::printf("  CRS: %s\n", m.epsg != 0 ? ("EPSG:" + std::to_string(m.epsg)).c_str() : "none (local frame)");
  const double cell_m2 = m.grid.cellSize() * m.grid.cellSize();
  std::printf("  cells known: %zu of %zu (%.1f m^2): %zu traversable, %zu non-traversable\n",
              gs.known, gs.cells, gs.known * cell_m2, gs.traversable, gs.non_traversable);
  std::printf("  octree: %.3g m voxels, %zu leaves, %zu occupied, %zu non-traversable\n",
              m.tree->getResolution(), os.leaves, os.occupied_leaves, os.non_traversable_leaves);
  std::printf("  memory: grid %.1f MiB, octree %.1f MiB\n", gs.memory_bytes / 1048576.0,
              os.memory_bytes / 1048576.0);
  std::printf("  map.tif bands:");
  int b = 1;
  for (const auto& band : gdal::geoTiffBands()) std::printf(" %d %s [%s];", b++, band.name, band.unit);
  std::printf("\n  files:");
  for (const auto& f : mapFileNames()) {
    if (fs::exists(m.dir / f)) std::printf(" %s (%ju B)", f.c_str(), static_cast<std::uintmax_t>(fs::file_size(m.dir / f)));
  }
  std::printf("\n");
  return 0;
}

int runMap(const std::vector<std::string>& argv) {
  if (argv.empty()) throw UsageError("expected a subcommand: info, merge or crop");
  const std::vector<std::string> rest(argv.begin() + 1, argv.end());
  if (argv[0] == "info") return runMapInfo(rest);
  if (argv[0] == "merge") return runMapMerge(rest);
  if (argv[0] == "crop") return runMapCrop(rest);
  throw UsageError("unknown subcommand '" + argv[0] + "' (info, merge or crop)");
}

}  // namespace upd::app
