#include "upd/maps/step_edges.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace upd::maps {

void StepEdgeParams::validate() const {
  const char* s = "StepEdgeParams";
  core::requireParam(std::isfinite(max_step_m) && max_step_m > 0, s, "max_step_m", max_step_m,
                     "must be > 0");
  core::requireParam(min_hits >= 1, s, "min_hits", min_hits, "must be >= 1");
  core::requireParam(std::isfinite(range_m) && range_m > 0, s, "range_m", range_m, "must be > 0");
  core::requireParam(std::isfinite(bump_height_m) && bump_height_m > 0, s, "bump_height_m",
                     bump_height_m, "must be > 0");
  core::requireParam(std::isfinite(bump_edge_m) && bump_edge_m > 0 && bump_edge_m <= bump_height_m,
                     s, "bump_edge_m", bump_edge_m, "must be in (0, bump_height_m]");
  core::requireParam(std::isfinite(bump_ring_inner_m) && bump_ring_inner_m > 0, s,
                     "bump_ring_inner_m", bump_ring_inner_m, "must be > 0");
  core::requireParam(std::isfinite(bump_ring_outer_m) && bump_ring_outer_m > bump_ring_inner_m, s,
                     "bump_ring_outer_m", bump_ring_outer_m, "must be > bump_ring_inner_m");
  core::requireParam(std::isfinite(bump_fit_tolerance_m) && bump_fit_tolerance_m > 0, s,
                     "bump_fit_tolerance_m", bump_fit_tolerance_m, "must be > 0");
  core::requireParam(std::isfinite(bump_min_zeta) && bump_min_zeta >= 0 && bump_min_zeta <= 1, s,
                     "bump_min_zeta", bump_min_zeta, "must be in [0, 1]");
  core::requireParam(std::isfinite(bump_min_inliers) && bump_min_inliers > 0 &&
                         bump_min_inliers <= 1,
                     s, "bump_min_inliers", bump_min_inliers, "must be in (0, 1]");
  core::requireParam(std::isfinite(bump_border_m) && bump_border_m >= 0, s, "bump_border_m",
                     bump_border_m, "must be >= 0");
}

namespace {

// Mean elevation of window cell (cx, cy); NaN when outside or with fewer than min_hits points.
double cellHeight(const TraversabilityGrid& grid, int cx, int cy, int min_hits) {
  if (cx < 0 || cy < 0 || cx >= grid.sizeX() || cy >= grid.sizeY()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  const GridCell& c = grid.at(cx, cy);
  return c.hits >= static_cast<std::uint32_t>(min_hits) && std::isfinite(c.elevation_m)
             ? static_cast<double>(c.elevation_m)
             : std::numeric_limits<double>::quiet_NaN();
}

// The window cell nearest to centre_xy (clamped into the window); false when there is none.
bool centreCell(const TraversabilityGrid& grid, const Eigen::Vector2d& centre_xy, int& cx,
                int& cy) {
  const double half = 0.5 * grid.cellSize();
  return grid.cellIndex(std::clamp(centre_xy.x(), grid.xMin(), grid.xMax() - half),
                        std::clamp(centre_xy.y(), grid.yMin(), grid.yMax() - half), cx, cy);
}

struct Offset {
  int dx, dy;
};

// The ground plane round a cell: z = a + b dx + c dy in cell offsets from it.
struct RingPlane {
  Eigen::Vector3d coef = Eigen::Vector3d::Zero();
  double at(int dx, int dy) const { return coef[0] + coef[1] * dx + coef[2] * dy; }
};

// Least-squares plane through the ring's known cells whose residual against `previous` is within
// tolerance (all of them when previous is null); false when fewer than three such cells or a
// degenerate fit. inliers: the cells used.
bool fitRing(const std::vector<Offset>& ring, const std::vector<double>& h,
             const RingPlane* previous, double tolerance_m, RingPlane& plane, int& inliers) {
  Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
  Eigen::Vector3d atb = Eigen::Vector3d::Zero();
  inliers = 0;
  for (std::size_t k = 0; k < ring.size(); ++k) {
    if (!std::isfinite(h[k])) continue;
    const bool off = previous != nullptr &&
                     std::abs(h[k] - previous->at(ring[k].dx, ring[k].dy)) > tolerance_m;
    if (off) continue;
    const Eigen::Vector3d row(1.0, ring[k].dx, ring[k].dy);
    ata += row * row.transpose();
    atb += row * h[k];
    ++inliers;
  }
  if (inliers < 3) return false;
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(ata);
  if (ldlt.info() != Eigen::Success) return false;
  plane.coef = ldlt.solve(atb);
  return plane.coef.allFinite();
}

// The bump check's cell offsets: the ground ring and the disc inside it, in cells.
// The cell offsets whose distance from the centre lies in [r_min, r_max] cells (a small tolerance
// above r_max, so that a radius of exactly n cells keeps the cells n away).
std::vector<Offset> offsetsWithin(double r_min, double r_max) {
  std::vector<Offset> out;
  const int reach = static_cast<int>(std::ceil(r_max));
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      const double r = std::hypot(dx, dy);
      if (r >= r_min && r <= r_max + 1e-9) out.push_back({dx, dy});
    }
  }
  return out;
}

struct BumpShape {
  std::vector<Offset> ring;
  std::vector<Offset> border;  // within bump_border_m of a bump cell's centre (itself included)
  int border_cells = 0;        // the border's reach [cells]
  int radius = 0;     // the disc's offsets are below `inner` cells: within radius of the cell
  double inner = 0.0;  // the ring's inner radius [cells]
  int side() const { return 2 * radius + 1; }
  std::size_t discIndex(const Offset& o) const {
    return static_cast<std::size_t>(o.dy + radius) * side() + (o.dx + radius);
  }
};

BumpShape bumpShape(const StepEdgeParams& params, double cell) {
  BumpShape b;
  b.inner = params.bump_ring_inner_m / cell;
  b.ring = offsetsWithin(b.inner, params.bump_ring_outer_m / cell);
  b.radius = static_cast<int>(std::ceil(b.inner));
  const double border = params.bump_border_m / cell;
  b.border = offsetsWithin(0.0, border);
  b.border_cells = static_cast<int>(std::floor(border + 1e-9));
  return b;
}

// The plane of the ground ring round cell (cx, cy) when the ring is one plane and the cell
// stands more than bump_height_m above it (see the header comment); false otherwise.
bool bumpPlane(const TraversabilityGrid& grid, int cx, int cy, const BumpShape& shape,
               const StepEdgeParams& params, std::vector<double>& h, RingPlane& plane) {
  const double hc = cellHeight(grid, cx, cy, params.min_hits);
  if (!std::isfinite(hc)) return false;
  int known = 0;
  double lowest = std::numeric_limits<double>::infinity();
  h.resize(shape.ring.size());
  for (std::size_t k = 0; k < shape.ring.size(); ++k) {
    h[k] = cellHeight(grid, cx + shape.ring[k].dx, cy + shape.ring[k].dy, params.min_hits);
    known += std::isfinite(h[k]) ? 1 : 0;
    lowest = std::fmin(lowest, h[k]);
  }
  // Half the ring known at least: a cell at the edge of the observed ground decides nothing.
  if (known < static_cast<int>(shape.ring.size() / 2)) return false;
  // The plane lies above the lowest ground cell less the tolerance: most cells end here.
  if (!(hc - lowest > params.bump_height_m - params.bump_fit_tolerance_m)) return false;
  RingPlane first;
  int n_first = 0, n_fit = 0;
  if (!fitRing(shape.ring, h, nullptr, 0.0, first, n_first)) return false;
  if (!fitRing(shape.ring, h, &first, params.bump_fit_tolerance_m, plane, n_fit)) return false;
  int fitting = 0;  // the ring cells within the tolerance of the refitted plane
  for (std::size_t k = 0; k < shape.ring.size(); ++k) {
    const double residual = h[k] - plane.at(shape.ring[k].dx, shape.ring[k].dy);
    fitting += std::abs(residual) <= params.bump_fit_tolerance_m;  // false for NaN
  }
  return fitting >= params.bump_min_inliers * known && hc - plane.at(0, 0) > params.bump_height_m;
}

// The bump's body round cell (cx, cy): the cells connected to it inside the disc standing more
// than bump_edge_m above the plane, as offsets. False when the raised ground reaches the ring (a
// platform or a ramp, not a rock).
bool bumpBody(const TraversabilityGrid& grid, int cx, int cy, const BumpShape& shape,
              const RingPlane& plane, const StepEdgeParams& params, std::vector<Offset>& body) {
  std::vector<std::uint8_t> seen(static_cast<std::size_t>(shape.side()) * shape.side(), 0);
  std::vector<Offset> stack{{0, 0}};
  seen[shape.discIndex({0, 0})] = 1;
  body.clear();
  while (!stack.empty()) {
    const Offset o = stack.back();
    stack.pop_back();
    body.push_back(o);
    constexpr int kNext[4][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}};
    for (const auto& d : kNext) {
      const Offset n{o.dx + d[0], o.dy + d[1]};
      if (std::abs(n.dx) > shape.radius || std::abs(n.dy) > shape.radius) return false;
      if (seen[shape.discIndex(n)]) continue;
      seen[shape.discIndex(n)] = 1;
      const double hq = cellHeight(grid, cx + n.dx, cy + n.dy, params.min_hits);
      if (!(hq - plane.at(n.dx, n.dy) > params.bump_edge_m)) continue;
      if (std::hypot(n.dx, n.dy) >= shape.inner) return false;
      stack.push_back(n);
    }
  }
  // Smooth to the UPD throughout; a cell never scored by it (an oracle's or baseline's map)
  // decides nothing.
  for (const Offset& o : body) {
    const float zeta = grid.at(cx + o.dx, cy + o.dy).zeta_min;
    if (!(zeta >= params.bump_min_zeta)) return false;
  }
  return true;
}

}  // namespace

std::vector<Eigen::Vector2d> findBumps(const TraversabilityGrid& grid,
                                       const Eigen::Vector2d& centre_xy,
                                       const StepEdgeParams& params) {
  params.validate();
  std::vector<Eigen::Vector2d> out;
  if (!params.enabled || !params.bumps) return out;
  const int nx = grid.sizeX(), ny = grid.sizeY();
  const double cell = grid.cellSize();
  int cx0, cy0;
  if (!centreCell(grid, centre_xy, cx0, cy0)) return out;
  const BumpShape shape = bumpShape(params, cell);
  // The bump cells found so far (1: a bump's body, 2: its border), over the checked cells' box
  // grown by the disc and the border.
  const int reach = static_cast<int>(std::ceil(params.range_m / cell));
  const int grow = shape.radius + shape.border_cells;
  const int bx0 = std::max(0, cx0 - reach - grow), by0 = std::max(0, cy0 - reach - grow);
  const int bx1 = std::min(nx - 1, cx0 + reach + grow), by1 = std::min(ny - 1, cy0 + reach + grow);
  const int bw = bx1 - bx0 + 1;
  std::vector<std::uint8_t> bump(static_cast<std::size_t>(bw) * (by1 - by0 + 1), 0);
  const auto idx = [&](int cx, int cy) {
    return static_cast<std::size_t>(cy - by0) * bw + (cx - bx0);
  };
  const double r2 = params.range_m * params.range_m;
  std::vector<double> h;
  std::vector<Offset> body;
  for (int cy = std::max(0, cy0 - reach); cy <= std::min(ny - 1, cy0 + reach); ++cy) {
    for (int cx = std::max(0, cx0 - reach); cx <= std::min(nx - 1, cx0 + reach); ++cx) {
      if ((grid.cellCenter(cx, cy) - centre_xy).squaredNorm() > r2) continue;
      if (bump[idx(cx, cy)] == 1) continue;  // inside a bump found from another cell
      // A bump's body holds the cell it starts from and is smooth to the UPD throughout
      // (bumpBody): a cell not read smooth starts none, so its ring is not fitted (on an
      // oracle's or the baseline's map, which hold no zeta, no cell's is).
      if (!(grid.at(cx, cy).zeta_min >= params.bump_min_zeta)) continue;
      RingPlane plane;
      if (!bumpPlane(grid, cx, cy, shape, params, h, plane)) continue;
      if (!bumpBody(grid, cx, cy, shape, plane, params, body)) continue;
      for (const Offset& o : body) {
        for (const Offset& d : shape.border) {
          const int qx = cx + o.dx + d.dx, qy = cy + o.dy + d.dy;
          if (qx < bx0 || qy < by0 || qx > bx1 || qy > by1) continue;
          std::uint8_t& b = bump[idx(qx, qy)];
          b = d.dx == 0 && d.dy == 0 ? 1 : std::max<std::uint8_t>(b, 2);
        }
      }
    }
  }
  for (int cy = by0; cy <= by1; ++cy) {
    for (int cx = bx0; cx <= bx1; ++cx) {
      if (bump[idx(cx, cy)] != 0) out.push_back(grid.cellCenter(cx, cy));
    }
  }
  return out;
}

std::vector<Eigen::Vector2d> findStepEdges(const TraversabilityGrid& grid,
                                           const Eigen::Vector2d& centre_xy,
                                           const StepEdgeParams& params) {
  params.validate();
  std::vector<Eigen::Vector2d> out;
  if (!params.enabled) return out;
  const int nx = grid.sizeX(), ny = grid.sizeY();
  const double cell = grid.cellSize();
  const auto height = [&](int cx, int cy) { return cellHeight(grid, cx, cy, params.min_hits); };
  int cx0, cy0;
  if (!centreCell(grid, centre_xy, cx0, cy0)) return out;
  const int reach = static_cast<int>(std::ceil(params.range_m / cell));
  const double r2 = params.range_m * params.range_m;
  constexpr int kDirs[2][2] = {{1, 0}, {0, 1}};
  for (int cy = std::max(0, cy0 - reach); cy <= std::min(ny - 1, cy0 + reach); ++cy) {
    for (int cx = std::max(0, cx0 - reach); cx <= std::min(nx - 1, cx0 + reach); ++cx) {
      const Eigen::Vector2d c = grid.cellCenter(cx, cy);
      if ((c - centre_xy).squaredNorm() > r2) continue;
      for (const auto& d : kDirs) {
        // The ground of each side extrapolated to c; NaN when a cell has too few points.
        const double lo = height(cx - d[0], cy - d[1]), hi = height(cx + d[0], cy + d[1]);
        const double below = 2.0 * lo - height(cx - 2 * d[0], cy - 2 * d[1]);
        const double above = 2.0 * hi - height(cx + 2 * d[0], cy + 2 * d[1]);
        // Comparisons with NaN are false: a missing cell finds no edge.
        if (std::abs(above - below) > params.max_step_m && std::abs(hi - lo) > params.max_step_m) {
          out.push_back(c);
          break;
        }
      }
    }
  }
  return out;
}

}  // namespace upd::maps
