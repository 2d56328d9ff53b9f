#include "map_folder.h"

#include "upd/gdal/geotiff.h"
#include "upd/io/atomic_file.h"
#include "upd/io/json_io.h"
#include "upd/maps/grid_export.h"
#include "upd/nav/scene_objects.h"

#include <mrpt/io/CMemoryStream.h>
#include <mrpt/io/zip.h>
#include <mrpt/opengl/CGridPlaneXY.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CPointCloudColoured.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/serialization/CArchive.h>

#include <cmath>
#include <fstream>
#include <stdexcept>

namespace upd::app {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::shared_ptr<mrpt::opengl::CPointCloudColoured> gridCells(
    const maps::TraversabilityGrid& grid) {
  auto cells = mrpt::opengl::CPointCloudColoured::Create();
  cells->setPointSize(4.0f);
  maps::forEachKnownCell(grid, [&](int cx, int cy, const maps::GridCell& c) {
    const auto xy = grid.cellCenter(cx, cy);
    const auto rgb = maps::traversabilityColourRgb(maps::probabilityOf(c, grid.params()));
    const float z = std::isfinite(c.elevation_m) ? c.elevation_m : 0.f;
    cells->push_back(static_cast<float>(xy.x()), static_cast<float>(xy.y()), z, rgb[0] / 255.f,
                     rgb[1] / 255.f, rgb[2] / 255.f);
  });
  return cells;
}

// The grid's known cells and the trajectory as an MRPT scene (SceneViewer3D), written as
// COpenGLScene::saveToFile does (gzip, level 1) but through io::writeFileAtomically.
void write3DScene(const maps::TraversabilityGrid& grid,
                  const std::vector<Eigen::Vector3d>& trajectory, const std::string& path) {
  mrpt::opengl::COpenGLScene scene;
  auto plane = mrpt::opengl::CGridPlaneXY::Create(
      static_cast<float>(grid.xMin()), static_cast<float>(grid.xMax()),
      static_cast<float>(grid.yMin()), static_cast<float>(grid.yMax()), 0, 1.0f);
  plane->setColor(0.7, 0.7, 0.7, 0.4);
  scene.insert(plane);
  scene.insert(gridCells(grid));
  auto path_lines = nav::newSetOfLines();
  path_lines->setColor(0.1, 0.2, 0.9);
  path_lines->setLineWidth(3);
  for (std::size_t k = 1; k < trajectory.size(); ++k) {
    const auto& a = trajectory[k - 1];
    const auto& b = trajectory[k];
    path_lines->appendLine(a.x(), a.y(), a.z() + 0.05, b.x(), b.y(), b.z() + 0.05);
  }
  scene.insert(path_lines);
  mrpt::io::CMemoryStream mem;
  mrpt::serialization::archiveFrom(mem) << scene;
  const auto* bytes = static_cast<const std::uint8_t*>(mem.getRawBufferData());
  const std::vector<std::uint8_t> raw(bytes, bytes + mem.getTotalBytesCount());
  std::vector<std::uint8_t> gz;
  if (!mrpt::io::zip::compress_gz_data_block(raw, gz, 1)) {
    throw std::runtime_error("cannot compress " + path);
  }
  io::writeFileAtomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(gz.data()), static_cast<std::streamsize>(gz.size()));
  });
}

}  // namespace

const std::vector<std::string>& mapFileNames() {
  static const std::vector<std::string> names{
      "map.png",  "map.pgm",       "map.yaml",
      "map_cost.pgm", "map_cost.yaml", "map.tif",
      "map.ot",   "map_colour.ot", "map_traversability.ot",
      "map.bt",   "map.3Dscene"};
  return names;
}

void writeMapFiles(const maps::TraversabilityGrid& grid, maps::TraversabilityOcTree& tree,
                   const std::vector<Eigen::Vector3d>& trajectory, const fs::path& dir,
                   int epsg) {
  const std::string map = (dir / "map").string();
  // The GeoTIFF first: an unknown --epsg fails before any file is written.
  gdal::writeGeoTiff(grid, map + ".tif", {epsg});
  maps::writeColourPng(grid, map + ".png");
  maps::writeRosMap(grid, map);
  maps::writeRosCostMap(grid, (dir / "map_cost").string());
  tree.updateInnerOccupancy();
  // map.ot is a standard ColorOcTree so that convert_octree, octovis and AbstractOcTree::read
  // open it; the custom node type would need our library registered in the reading program.
  maps::writeColourOt(tree, map + ".ot");
  maps::writeColourOt(tree, map + "_colour.ot");  // the name earlier versions wrote
  maps::writeTraversabilityOt(tree, map + "_traversability.ot");
  maps::writeOccupancyBt(tree, map + ".bt");
  write3DScene(grid, trajectory, map + ".3Dscene");
}

json gridJson(const maps::TraversabilityGrid& grid) {
  const maps::GridStats gs = maps::computeStats(grid);
  return {{"cell_size_m", grid.cellSize()},
          {"cells", gs.cells},
          {"known", gs.known},
          {"traversable", gs.traversable},
          {"non_traversable", gs.non_traversable},
          {"memory_bytes", gs.memory_bytes},
          {"x_min_m", grid.xMin()}, {"y_min_m", grid.yMin()},
          {"x_max_m", grid.xMax()}, {"y_max_m", grid.yMax()}};
}

json octreeJson(const maps::TraversabilityOcTree& tree) {
  const maps::OctreeStats os = maps::computeStats(tree);
  return {{"resolution_m", tree.getResolution()},
          {"leaves", os.leaves},
          {"occupied_leaves", os.occupied_leaves},
          {"non_traversable_leaves", os.non_traversable_leaves},
          {"memory_bytes", os.memory_bytes}};
}

MapFolder readMapFolder(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw std::runtime_error(dir.string() + ": not a directory");
  for (const char* f : {"map.tif", "map_traversability.ot"}) {
    if (!fs::exists(dir / f)) {
      throw std::runtime_error((dir / f).string() + ": not found (not a map folder of upd playback)");
    }
  }
  gdal::GeoTiffMap tif = gdal::readGeoTiff((dir / "map.tif").string());
  MapFolder m{dir, std::move(tif.grid), maps::readTraversabilityOt((dir / "map_traversability.ot").string()),
              tif.epsg, nullptr};
  if (fs::exists(dir / "summary.json")) {
    std::ifstream in(dir / "summary.json");
    m.summary = json::parse(in, nullptr, false);
    if (m.summary.is_discarded()) {
      throw std::runtime_error((dir / "summary.json").string() + ": not valid JSON");
    }
  }
  return m;
}

std::vector<std::string> sourceRawlogs(const json& summary) {
  std::vector<std::string> out;
  if (!summary.is_object()) return out;
  if (summary.contains("rawlogs")) {
    for (const auto& r : summary["rawlogs"]) out.push_back(r.get<std::string>());
  } else if (summary.contains("rawlog")) {
    out.push_back(summary["rawlog"].get<std::string>());
  }
  return out;
}

void writeMapFolder(const maps::TraversabilityGrid& grid, maps::TraversabilityOcTree& tree,
                    int epsg, const fs::path& dir, json extra) {
  fs::create_directories(dir);
  writeMapFiles(grid, tree, {}, dir, epsg);
  extra["grid"] = gridJson(grid);
  extra["octree"] = octreeJson(tree);
  if (epsg != 0) extra["epsg"] = epsg;
  extra["outputs"] = mapFileNames();
  io::writeJsonAtomically((dir / "summary.json").string(), extra);
}

}  // namespace upd::app
