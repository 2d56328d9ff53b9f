// Map snapshots (the grid's cells, the tree's voxels, the path) and their MRPT objects; the
// headless map figure of `upd render DIR` (map_view.h).
#include "upd/nav/map_view.h"
#include "figure_scene.h"
#include "map_scene.h"
#include "upd/nav/scene_objects.h"

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/opengl/CBox.h>
#include <mrpt/opengl/COctoMapVoxels.h>
#include <mrpt/opengl/COpenGLScene.h>
#include <mrpt/opengl/CSetOfLines.h>
#include <mrpt/opengl/CSetOfTriangles.h>
#include <mrpt/serialization/CArchive.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace upd::nav {

MapStyle parseMapStyle(const std::string& name) {
  if (name == "grid") return MapStyle::Grid;
  if (name == "octree") return MapStyle::Octree;
  if (name == "none") return MapStyle::None;
  throw std::invalid_argument("unknown map style '" + name + "' (grid, octree, none)");
}

bool MapSnapshot::bounds(Eigen::Vector3f& lo, Eigen::Vector3f& hi) const {
  detail::Frame f;
  for (int cy = 0; cy < ny; ++cy) {
    for (int cx = 0; cx < nx; ++cx) {
      const MapCellView& c = cells[std::size_t(cy) * std::size_t(nx) + std::size_t(cx)];
      if (c.label == core::Label::Unknown) continue;
      const float z = std::isfinite(c.z) ? c.z : 0.0f;
      f.extend({float(x_min + (cx + 0.5) * cell_m), float(y_min + (cy + 0.5) * cell_m), z});
    }
  }
  for (const auto& v : voxels) f.extend(v.centre);
  for (const auto& p : path) f.extend(p);
  lo = f.lo;
  hi = f.hi;
  return !f.empty();
}

void snapshotGrid(const maps::TraversabilityGrid& grid, MapSnapshot& out) {
  out.x_min = grid.xMin();
  out.y_min = grid.yMin();
  out.cell_m = grid.cellSize();
  out.nx = grid.sizeX();
  out.ny = grid.sizeY();
  out.cells.assign(std::size_t(out.nx) * std::size_t(out.ny), MapCellView{});
  maps::forEachKnownCell(grid, [&](int cx, int cy, const maps::GridCell& c) {
    MapCellView& v = out.cells[std::size_t(cy) * std::size_t(out.nx) + std::size_t(cx)];
    v.z = c.elevation_m;
    v.zeta = c.zeta_min;
    v.cost = c.cost_mean;
    v.slope_deg = c.slope_rad * float(180.0 / M_PI);
    v.label = maps::labelOf(c, grid.params());
  });
}

void snapshotOctree(const maps::TraversabilityOcTree& tree, MapSnapshot& out, double p_nontrav_threshold) {
  out.voxels.clear();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    MapVoxelView v;
    v.centre = Eigen::Vector3f(float(it.getX()), float(it.getY()), float(it.getZ()));
    v.size = float(it.getSize());
    v.zeta = it->getZetaMin();
    v.cost = it->getCostMean();
    const float p = it->getNonTraversableProbability();
    if (std::isfinite(p)) {
      v.label = p >= p_nontrav_threshold ? core::Label::NonTraversable : core::Label::Traversable;
    }
    out.voxels.push_back(v);
  }
}

std::vector<Eigen::Vector3f> readScenePath(const std::string& scene_file) {
  mrpt::opengl::COpenGLScene scene;
  try {
    mrpt::io::CFileGZInputStream in(scene_file);
    mrpt::serialization::archiveFrom(in) >> scene;
  } catch (const std::exception& e) {
    std::string first = e.what();
    throw std::runtime_error(scene_file + ": not an MRPT scene (" + first.substr(0, first.find('\n')) + ")");
  }
  std::vector<Eigen::Vector3f> path;
  const auto lines = scene.getByClass<mrpt::opengl::CSetOfLines>();
  if (!lines) return path;
  for (auto it = lines->begin(); it != lines->end(); ++it) {
    const mrpt::math::TSegment3D& s = *it;
    if (path.empty()) path.emplace_back(float(s.point1.x), float(s.point1.y), float(s.point1.z - 0.05));
    path.emplace_back(float(s.point2.x), float(s.point2.y), float(s.point2.z - 0.05));
  }
  return path;
}

namespace detail {
namespace {

Rgb cellColor(const MapCellView& c, FigureColor mode, float z_lo, float z_hi) {
  switch (mode) {
    case FigureColor::Zeta: return zetaColor(c.zeta);
    case FigureColor::Label: return labelColor(c.label);
    case FigureColor::Cost: return costColor(c.cost);
    case FigureColor::Slope: return slopeColor(c.slope_deg);
    case FigureColor::Height: return heightColor(c.z, z_lo, z_hi);
    case FigureColor::Rgb: return {150, 150, 150};  // map cells carry no camera colour
  }
  return {};
}

// The grid's known cells as flat squares at their elevation, 2 cm below the points. Lit:
// MRPT 2.5 draws unlit triangles and textures over everything else (no depth test against
// the other shaders), so the robot and the cloud would vanish under the map. A grid of more
// than a million cells is sampled.
mrpt::opengl::CRenderizable::Ptr gridTiles(const MapSnapshot& m, FigureColor mode, float z_lo, float z_hi) {
  const int step = std::max(1, int(std::ceil(std::sqrt(double(m.nx) * m.ny / 1e6))));
  auto tris = mrpt::opengl::CSetOfTriangles::Create();
  tris->enableLight(true);
  const float half = float(0.5 * m.cell_m * step);
  for (int cy = 0; cy < m.ny; cy += step) {
    for (int cx = 0; cx < m.nx; cx += step) {
      const MapCellView& c = m.cells[std::size_t(cy) * std::size_t(m.nx) + std::size_t(cx)];
      if (c.label == core::Label::Unknown) continue;
      const Rgb col = cellColor(c, mode, z_lo, z_hi);
      const float x = float(m.x_min + (cx + 0.5 * step) * m.cell_m), y = float(m.y_min + (cy + 0.5 * step) * m.cell_m);
      const float z = (std::isfinite(c.z) ? c.z : 0.0f) - 0.02f;
      const mrpt::math::TPoint3Df a(x - half, y - half, z), b(x + half, y - half, z), d(x + half, y + half, z),
          e(x - half, y + half, z);
      for (auto t : {mrpt::opengl::TTriangle(a, b, d), mrpt::opengl::TTriangle(a, d, e)}) {
        t.setColor(mrpt::img::TColor(col.r, col.g, col.b));
        tris->insertTriangle(t);
      }
    }
  }
  return tris;
}

mrpt::opengl::CRenderizable::Ptr octreeVoxels(const MapSnapshot& m, FigureColor mode, float z_lo, float z_hi) {
  auto vox = mrpt::opengl::COctoMapVoxels::Create();
  vox->resizeVoxelSets(1);
  vox->reserveVoxels(0, m.voxels.size());
  vox->enableLights(true);
  vox->enableCubeTransparency(false);
  vox->showGridLines(false);
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo;
  for (const auto& v : m.voxels) {
    MapCellView as_cell;
    as_cell.z = v.centre.z();
    as_cell.zeta = v.zeta;
    as_cell.cost = v.cost;
    as_cell.label = v.label;
    const Rgb c = cellColor(as_cell, mode, z_lo, z_hi);  // slope: grey (a voxel has none)
    vox->push_back_Voxel(0, {{v.centre.x(), v.centre.y(), v.centre.z()}, v.size, mrpt::img::TColor(c.r, c.g, c.b)});
    lo = lo.cwiseMin(v.centre);
    hi = hi.cwiseMax(v.centre);
  }
  if (!m.voxels.empty()) vox->setBoundingBox({lo.x(), lo.y(), lo.z()}, {hi.x(), hi.y(), hi.z()});
  return vox;
}

// A polyline through points, lifted by dz [m] above them.
mrpt::opengl::CSetOfLines::Ptr polyline(const std::vector<Eigen::Vector3f>& points, mrpt::img::TColor colour,
                                        float width, float dz) {
  auto lines = newSetOfLines();
  lines->setColor_u8(colour);
  lines->setLineWidth(width);
  for (std::size_t k = 1; k < points.size(); ++k) {
    const auto& a = points[k - 1];
    const auto& b = points[k];
    lines->appendLine(a.x(), a.y(), a.z() + dz, b.x(), b.y(), b.z() + dz);
  }
  return lines;
}

void addPathAndRobot(const MapSnapshot& m, mrpt::opengl::CSetOfObjects& set) {
  if (m.path.empty()) return;
  set.insert(polyline(m.path, mrpt::img::TColor(20, 20, 20), 3.0f, 0.08f));
  if (m.route.size() > 1) set.insert(polyline(m.route, mrpt::img::TColor(40, 90, 230), 2.0f, 0.06f));
  const Eigen::Vector3f end = m.path.back();
  float yaw = std::isfinite(m.robot_yaw_rad) ? m.robot_yaw_rad : 0.f;
  // Without a heading: that of the last segment of some length.
  for (std::size_t k = m.path.size(); !std::isfinite(m.robot_yaw_rad) && k-- > 1;) {
    const Eigen::Vector3f d = end - m.path[k - 1];
    if (d.head<2>().norm() > 0.05f) {
      yaw = std::atan2(d.y(), d.x());
      break;
    }
  }
  const float hl = 0.5f * m.robot_length_m, hw = 0.5f * m.robot_width_m;
  auto body = mrpt::opengl::CBox::Create(mrpt::math::TPoint3D(-hl, -hw, 0), mrpt::math::TPoint3D(hl, hw, 0.3));
  body->setColor_u8(mrpt::img::TColor(245, 130, 20));
  body->enableBoxBorder(true);
  body->setPose(mrpt::poses::CPose3D(end.x(), end.y(), end.z(), yaw, 0, 0));
  set.insert(body);
}

}  // namespace

mrpt::opengl::CSetOfObjects::Ptr mapObjects(const MapSnapshot& map, MapStyle style, FigureColor mode,
                                            float z_lo, float z_hi) {
  auto set = mrpt::opengl::CSetOfObjects::Create();
  if (style == MapStyle::Grid && map.hasGrid()) set->insert(gridTiles(map, mode, z_lo, z_hi));
  if (style == MapStyle::Octree && !map.voxels.empty()) set->insert(octreeVoxels(map, mode, z_lo, z_hi));
  addPathAndRobot(map, *set);
  return set;
}

}  // namespace detail

void renderMapFigure(const MapSnapshot& map, MapStyle style, const ScoredCloud* cloud,
                     const RenderOptions& options, const std::string& png) {
  detail::Frame f;
  if (cloud != nullptr) f = detail::upright(*cloud, Eigen::Vector3f::UnitZ());
  Eigen::Vector3f lo, hi;
  if (map.bounds(lo, hi)) f.extend(lo), f.extend(hi);
  if (f.empty()) throw std::invalid_argument("nothing to render: the map has no known cell and no path");
  f.n.clear();  // the camera's side: fixed for maps (the cloud's normals would pick it per frame)
  mrpt::opengl::COpenGLScene scene;
  scene.insert(detail::mapObjects(map, style, options.color, f.lo.z(), f.hi.z()));
  if (cloud != nullptr) {
    scene.insert(detail::cloudPoints(*cloud, f, options.color, options.point_size));
    if (options.normals) scene.insert(detail::normalLines(f));
  }
  detail::renderToPng(scene, f, options, 55.0, png);
}

}  // namespace upd::nav
