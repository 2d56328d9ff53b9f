#include "upd/maps/traversability_grid.h"

#include "upd/maps/fusion.h"

#include "grid_tiles.h"

#include <mrpt/containers/CDynamicGrid.h>

#include <cassert>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace upd::maps {

namespace {
// Larger windows would not fit a 32-bit cell index (and would not fit in memory anyway).
constexpr double kMaxCellsPerSide = 46000;
// The window's place is kept as 64-bit world cell indices (and in double, exact to 2^53): a
// centre farther out, only ever a corrupt pose or setting, would overflow the conversion.
constexpr double kMaxWorldCells = 1e15;
bool withinReach(double v_m, double cell_m) { return std::abs(v_m / cell_m) <= kMaxWorldCells; }
}  // namespace

void GridParams::validate() const {
  core::requireParam(std::isfinite(cell_size_m) && cell_size_m > 0, "GridParams", "cell_size_m",
               cell_size_m, "must be > 0");
  core::requireParam(std::isfinite(extent_m) && extent_m >= 2 * cell_size_m, "GridParams", "extent_m",
               extent_m, "must be at least two cells");
  core::requireParam(extent_m / cell_size_m <= kMaxCellsPerSide, "GridParams", "extent_m", extent_m,
               "gives more than 46000 cells per side (raise cell_size_m)");
  core::requireParam(extent_y_m == 0 || (std::isfinite(extent_y_m) && extent_y_m >= 2 * cell_size_m &&
                                         extent_y_m / cell_size_m <= kMaxCellsPerSide),
                     "GridParams", "extent_y_m", extent_y_m,
                     "must be 0 (= extent_m) or from two cells to 46000 cells");
  core::requireParam(tile_cells >= 8 && tile_cells <= 1024, "GridParams", "tile_cells", tile_cells,
                     "must be in [8, 1024]");
  core::requireParam(withinReach(center_x_m, cell_size_m), "GridParams", "center_x_m", center_x_m,
                     "must be finite and within 1e15 cells of the origin");
  core::requireParam(withinReach(center_y_m, cell_size_m), "GridParams", "center_y_m", center_y_m,
                     "must be finite and within 1e15 cells of the origin");
  core::requireParam(recenter_fraction > 0 && recenter_fraction < 0.5, "GridParams", "recenter_fraction",
               recenter_fraction, "must be in (0, 0.5)");
  core::requireParam(p_nontrav_threshold > 0 && p_nontrav_threshold < 1, "GridParams",
               "p_nontrav_threshold", p_nontrav_threshold, "must be in (0, 1)");
  core::requireParam(min_hits_known >= 1, "GridParams", "min_hits_known", min_hits_known, "must be >= 1");
}

int GridParams::cellsPerSide() const {
  return static_cast<int>(std::lround(extent_m / cell_size_m));
}
int GridParams::cellsY() const {
  return extent_y_m > 0 ? static_cast<int>(std::lround(extent_y_m / cell_size_m)) : cellsPerSide();
}

const char* layerName(GridLayer layer) {
  switch (layer) {
    case GridLayer::ProbabilityNonTraversable: return "p_nontrav";
    case GridLayer::LogOddsNonTraversable: return "logodds_nontrav";
    case GridLayer::ZetaMin: return "zeta_min";
    case GridLayer::ZetaMean: return "zeta_mean";
    case GridLayer::SlopeRad: return "slope_rad";
    case GridLayer::CostMean: return "cost_mean";
    case GridLayer::ElevationM: return "elevation_m";
    case GridLayer::ElevationMaxM: return "elevation_max_m";
    case GridLayer::Hits: return "hits";
    case GridLayer::LastSeenS: return "last_seen_s";
  }
  return "?";
}

float layerValue(const GridCell& cell, GridLayer layer) {
  switch (layer) {
    case GridLayer::ProbabilityNonTraversable: return probabilityFromLogOdds(cell.logodds_nontrav);
    case GridLayer::LogOddsNonTraversable: return cell.logodds_nontrav;
    case GridLayer::ZetaMin: return cell.zeta_min;
    case GridLayer::ZetaMean: return cell.zeta_mean;
    case GridLayer::SlopeRad: return cell.slope_rad;
    case GridLayer::CostMean: return cell.cost_mean;
    case GridLayer::ElevationM: return cell.elevation_m;
    case GridLayer::ElevationMaxM: return cell.elevation_max_m;
    case GridLayer::Hits: return static_cast<float>(cell.hits);
    case GridLayer::LastSeenS: return static_cast<float>(cell.last_seen_s);
  }
  return GridCell::kNaN;
}

struct TraversabilityGrid::Impl {
  mrpt::containers::CDynamicGrid<GridCell> cells;
  std::int64_t i0 = 0, j0 = 0;  // world index of cell (0, 0)
  int nx = 0, ny = 0;           // cells along x and y
  detail::GridTileStore tiles;  // cells kept from outside the window

  void allocate(double cell_size_m) {
    const GridCell unknown;
    cells.setSize(static_cast<double>(i0) * cell_size_m, static_cast<double>(i0 + nx) * cell_size_m,
                  static_cast<double>(j0) * cell_size_m, static_cast<double>(j0 + ny) * cell_size_m,
                  cell_size_m, &unknown);
    if (cells.getSizeX() != static_cast<std::size_t>(nx) ||
        cells.getSizeY() != static_cast<std::size_t>(ny)) {
      throw std::logic_error("TraversabilityGrid: CDynamicGrid allocated " +
                             std::to_string(cells.getSizeX()) + " x " +
                             std::to_string(cells.getSizeY()) + " cells instead of " +
                             std::to_string(nx) + " x " + std::to_string(ny));
    }
  }
  GridCell& at(int cx, int cy) { return *cells.cellByIndex(cx, cy); }
  bool contains(std::int64_t gi, std::int64_t gj) const {
    return gi >= i0 && gi < i0 + nx && gj >= j0 && gj < j0 + ny;
  }
  GridCell& atWorld(std::int64_t gi, std::int64_t gj) {
    return at(static_cast<int>(gi - i0), static_cast<int>(gj - j0));
  }
  // Calls f(tile key, first world cell of the tile) for every tile overlapping the window.
  template <class F>
  void forEachTile(F&& f) const {
    const std::int64_t t = tiles.tileCells();
    for (std::int64_t ty = detail::floorDiv(j0, t); ty * t < j0 + ny; ++ty) {
      for (std::int64_t tx = detail::floorDiv(i0, t); tx * t < i0 + nx; ++tx) {
        f(detail::TileKey{tx, ty}, tx * t, ty * t);
      }
    }
  }
  void keepCellsLeavingFor(const Impl& next);
  void restoreCellsEnteringFrom(const Impl& prev);
};

// Writes the cells of this window that `next` does not cover into their tiles.
void TraversabilityGrid::Impl::keepCellsLeavingFor(const Impl& next) {
  const std::int64_t t = tiles.tileCells();
  forEachTile([&](const detail::TileKey& key, std::int64_t gi0, std::int64_t gj0) {
    std::vector<GridCell> cells;
    for (std::int64_t gj = std::max(gj0, j0); gj < std::min(gj0 + t, j0 + ny); ++gj) {
      for (std::int64_t gi = std::max(gi0, i0); gi < std::min(gi0 + t, i0 + nx); ++gi) {
        if (next.contains(gi, gj)) continue;
        if (cells.empty()) cells = tiles.load(key);
        cells[static_cast<std::size_t>((gj - gj0) * t + (gi - gi0))] = atWorld(gi, gj);
      }
    }
    if (!cells.empty()) tiles.store(key, cells);
  });
}

// Fills the cells of this window that `prev` did not cover from their tiles, and forgets the
// tiles that now lie wholly inside the window (the window holds all their cells).
void TraversabilityGrid::Impl::restoreCellsEnteringFrom(const Impl& prev) {
  const std::int64_t t = tiles.tileCells();
  forEachTile([&](const detail::TileKey& key, std::int64_t gi0, std::int64_t gj0) {
    if (!tiles.has(key)) return;
    const std::vector<GridCell> cells = tiles.load(key);
    for (std::int64_t gj = std::max(gj0, j0); gj < std::min(gj0 + t, j0 + ny); ++gj) {
      for (std::int64_t gi = std::max(gi0, i0); gi < std::min(gi0 + t, i0 + nx); ++gi) {
        if (prev.contains(gi, gj)) continue;
        atWorld(gi, gj) = cells[static_cast<std::size_t>((gj - gj0) * t + (gi - gi0))];
      }
    }
    if (gi0 >= i0 && gi0 + t <= i0 + nx && gj0 >= j0 && gj0 + t <= j0 + ny) tiles.erase(key);
  });
}

TraversabilityGrid::TraversabilityGrid(const GridParams& params)
    : params_(params), impl_(std::make_unique<Impl>()) {
  params_.validate();
  impl_->nx = params_.cellsPerSide();
  impl_->ny = params_.cellsY();
  impl_->i0 = static_cast<std::int64_t>(std::floor(params_.center_x_m / params_.cell_size_m)) -
              impl_->nx / 2;
  impl_->j0 = static_cast<std::int64_t>(std::floor(params_.center_y_m / params_.cell_size_m)) -
              impl_->ny / 2;
  impl_->tiles = detail::GridTileStore(params_.tile_cells);
  impl_->allocate(params_.cell_size_m);
}

TraversabilityGrid::~TraversabilityGrid() = default;
TraversabilityGrid::TraversabilityGrid(const TraversabilityGrid& other)
    : params_(other.params_), impl_(std::make_unique<Impl>(*other.impl_)) {}
TraversabilityGrid& TraversabilityGrid::operator=(const TraversabilityGrid& other) {
  if (this != &other) {
    params_ = other.params_;
    impl_ = std::make_unique<Impl>(*other.impl_);
  }
  return *this;
}
TraversabilityGrid::TraversabilityGrid(TraversabilityGrid&&) noexcept = default;
TraversabilityGrid& TraversabilityGrid::operator=(TraversabilityGrid&&) noexcept = default;

int TraversabilityGrid::sizeX() const { return impl_->nx; }
int TraversabilityGrid::sizeY() const { return impl_->ny; }
std::int64_t TraversabilityGrid::originI() const { return impl_->i0; }
std::int64_t TraversabilityGrid::originJ() const { return impl_->j0; }
double TraversabilityGrid::xMin() const { return static_cast<double>(impl_->i0) * cellSize(); }
double TraversabilityGrid::yMin() const { return static_cast<double>(impl_->j0) * cellSize(); }
double TraversabilityGrid::xMax() const {
  return static_cast<double>(impl_->i0 + impl_->nx) * cellSize();
}
double TraversabilityGrid::yMax() const {
  return static_cast<double>(impl_->j0 + impl_->ny) * cellSize();
}

bool TraversabilityGrid::cellIndex(double x_m, double y_m, int& cx, int& cy) const {
  // floor, not CDynamicGrid::x2idx (which truncates towards zero and so folds the strip just
  // outside the lower edge into the first cell).
  return indexer()(x_m, y_m, cx, cy);
}

GridCellIndexer TraversabilityGrid::indexer() const {
  GridCellIndexer ix;
  ix.inv_cell = 1.0 / cellSize();
  ix.i0 = static_cast<double>(impl_->i0);
  ix.j0 = static_cast<double>(impl_->j0);
  ix.size_x = impl_->nx;
  ix.size_y = impl_->ny;
  return ix;
}

Eigen::Vector2d TraversabilityGrid::cellCenter(int cx, int cy) const {
  return {(static_cast<double>(impl_->i0 + cx) + 0.5) * cellSize(),
          (static_cast<double>(impl_->j0 + cy) + 0.5) * cellSize()};
}

const GridCell& TraversabilityGrid::at(int cx, int cy) const {
  assert(cx >= 0 && cx < impl_->nx && cy >= 0 && cy < impl_->ny);
  return *impl_->cells.cellByIndex(static_cast<unsigned>(cx), static_cast<unsigned>(cy));
}
GridCell& TraversabilityGrid::at(int cx, int cy) {
  assert(cx >= 0 && cx < impl_->nx && cy >= 0 && cy < impl_->ny);
  return impl_->at(cx, cy);
}

const GridCell* TraversabilityGrid::cellAt(double x_m, double y_m) const {
  int cx, cy;
  return cellIndex(x_m, y_m, cx, cy) ? &at(cx, cy) : nullptr;
}
GridCell* TraversabilityGrid::cellAt(double x_m, double y_m) {
  int cx, cy;
  return cellIndex(x_m, y_m, cx, cy) ? &at(cx, cy) : nullptr;
}

bool TraversabilityGrid::moveTo(const Eigen::Vector2d& robot_xy) {
  if (!params_.follow_robot) return false;
  core::requireParam(
      withinReach(robot_xy.x(), cellSize()) && withinReach(robot_xy.y(), cellSize()),
      "TraversabilityGrid::moveTo", "robot_xy",
      (std::ostringstream() << robot_xy.x() << "," << robot_xy.y()).str(),
      "must be finite and within 1e15 cells of the origin");
  const double ri = std::floor(robot_xy.x() / cellSize());
  const double rj = std::floor(robot_xy.y() / cellSize());
  const int nx = impl_->nx, ny = impl_->ny;
  if (std::abs(ri - (static_cast<double>(impl_->i0) + nx / 2)) <= params_.recenter_fraction * nx &&
      std::abs(rj - (static_cast<double>(impl_->j0) + ny / 2)) <= params_.recenter_fraction * ny) {
    return false;
  }
  auto moved = std::make_unique<Impl>();
  moved->nx = nx;
  moved->ny = ny;
  moved->i0 = static_cast<std::int64_t>(ri) - nx / 2;
  moved->j0 = static_cast<std::int64_t>(rj) - ny / 2;
  moved->allocate(cellSize());
  if (params_.keep_outside_window) impl_->keepCellsLeavingFor(*moved);
  // Copy the overlap, cell by world index: cells move whole, nothing is resampled.
  const std::int64_t gi_begin = std::max(impl_->i0, moved->i0);
  const std::int64_t gi_end = std::min(impl_->i0 + nx, moved->i0 + nx);
  const std::int64_t gj_begin = std::max(impl_->j0, moved->j0);
  const std::int64_t gj_end = std::min(impl_->j0 + ny, moved->j0 + ny);
  for (std::int64_t gj = gj_begin; gj < gj_end; ++gj) {
    for (std::int64_t gi = gi_begin; gi < gi_end; ++gi) {
      moved->at(static_cast<int>(gi - moved->i0), static_cast<int>(gj - moved->j0)) =
          impl_->at(static_cast<int>(gi - impl_->i0), static_cast<int>(gj - impl_->j0));
    }
  }
  moved->tiles = std::move(impl_->tiles);
  if (params_.keep_outside_window) moved->restoreCellsEnteringFrom(*impl_);
  impl_ = std::move(moved);
  return true;
}

void TraversabilityGrid::clear() {
  impl_->cells.fill(GridCell{});
  impl_->tiles = detail::GridTileStore(params_.tile_cells);
}

std::size_t TraversabilityGrid::windowBytes() const {
  return sizeof(Impl) + impl_->cells.data().capacity() * sizeof(GridCell);
}
std::size_t TraversabilityGrid::memoryBytes() const { return windowBytes() + storedTileBytes(); }
std::size_t TraversabilityGrid::storedTiles() const { return impl_->tiles.tiles(); }
std::size_t TraversabilityGrid::storedTileBytes() const { return impl_->tiles.bytes(); }
std::size_t TraversabilityGrid::maxTileBytes() const {
  return detail::GridTileStore::maxTileBytes(params_.tile_cells);
}

detail::GridTileStore GridStateAccess::allCells(const TraversabilityGrid& grid) {
  TraversabilityGrid::Impl copy = *grid.impl_;
  TraversabilityGrid::Impl nowhere;  // a window covering nothing: every cell leaves
  nowhere.i0 = nowhere.j0 = std::numeric_limits<std::int64_t>::min() / 2;
  copy.keepCellsLeavingFor(nowhere);
  return std::move(copy.tiles);
}

void GridStateAccess::restore(TraversabilityGrid& grid, std::int64_t i0, std::int64_t j0,
                              detail::GridTileStore tiles) {
  TraversabilityGrid::Impl& w = *grid.impl_;
  w.i0 = i0;
  w.j0 = j0;
  w.allocate(grid.cellSize());
  w.tiles = std::move(tiles);
  TraversabilityGrid::Impl nowhere;  // every cell of the window enters it
  nowhere.i0 = nowhere.j0 = std::numeric_limits<std::int64_t>::min() / 2;
  w.restoreCellsEnteringFrom(nowhere);
}

namespace {

// Bounding box of observed world cells [i_lo, i_hi] x [j_lo, j_hi]; empty while i_lo > i_hi.
struct CellBox {
  std::int64_t i_lo = std::numeric_limits<std::int64_t>::max(), i_hi = 0;
  std::int64_t j_lo = std::numeric_limits<std::int64_t>::max(), j_hi = 0;
  bool empty() const { return i_lo > i_hi; }
  void add(std::int64_t gi, std::int64_t gj) {
    if (empty()) {
      i_lo = i_hi = gi;
      j_lo = j_hi = gj;
      return;
    }
    i_lo = std::min(i_lo, gi), i_hi = std::max(i_hi, gi);
    j_lo = std::min(j_lo, gj), j_hi = std::max(j_hi, gj);
  }
};

}  // namespace

TraversabilityGrid TraversabilityGrid::wholeRun() const {
  const Impl& w = *impl_;
  const std::int64_t t = w.tiles.tileCells();
  CellBox box;
  for (int cy = 0; cy < w.ny; ++cy) {
    for (int cx = 0; cx < w.nx; ++cx) {
      if (at(cx, cy).observed()) box.add(w.i0 + cx, w.j0 + cy);
    }
  }
  w.tiles.forEachKey([&](const detail::TileKey& key) {
    const std::vector<GridCell> cells = w.tiles.load(key);
    for (std::int64_t k = 0; k < t * t; ++k) {
      if (cells[static_cast<std::size_t>(k)].observed()) {
        box.add(key.first * t + k % t, key.second * t + k / t);
      }
    }
  });
  GridParams p = params_;
  p.follow_robot = false;
  p.keep_outside_window = false;
  if (box.empty()) box = CellBox{w.i0, w.i0 + w.nx - 1, w.j0, w.j0 + w.ny - 1};
  const std::int64_t nx = std::max<std::int64_t>(2, box.i_hi - box.i_lo + 1);
  const std::int64_t ny = std::max<std::int64_t>(2, box.j_hi - box.j_lo + 1);
  p.extent_m = static_cast<double>(nx) * p.cell_size_m;
  p.extent_y_m = static_cast<double>(ny) * p.cell_size_m;
  // The centre whose floor(centre / cell) - n / 2 is the box's first cell.
  p.center_x_m = (static_cast<double>(box.i_lo + nx / 2) + 0.5) * p.cell_size_m;
  p.center_y_m = (static_cast<double>(box.j_lo + ny / 2) + 0.5) * p.cell_size_m;
  TraversabilityGrid out(p);
  Impl& o = *out.impl_;
  if (o.i0 != box.i_lo || o.j0 != box.j_lo) {
    throw std::logic_error("TraversabilityGrid::wholeRun: window placed off the observed cells");
  }
  w.tiles.forEachKey([&](const detail::TileKey& key) {
    const std::vector<GridCell> cells = w.tiles.load(key);
    for (std::int64_t k = 0; k < t * t; ++k) {
      const std::int64_t gi = key.first * t + k % t, gj = key.second * t + k / t;
      if (!w.contains(gi, gj) && o.contains(gi, gj)) o.atWorld(gi, gj) = cells[static_cast<std::size_t>(k)];
    }
  });
  for (int cy = 0; cy < w.ny; ++cy) {
    for (int cx = 0; cx < w.nx; ++cx) {
      if (o.contains(w.i0 + cx, w.j0 + cy)) o.atWorld(w.i0 + cx, w.j0 + cy) = at(cx, cy);
    }
  }
  return out;
}

bool isKnown(const GridCell& cell, const GridParams& params) {
  return cell.hits >= static_cast<std::uint32_t>(params.min_hits_known) &&
         !std::isnan(cell.logodds_nontrav);
}

core::Label labelOf(const GridCell& cell, const GridParams& params) {
  if (!isKnown(cell, params)) return core::Label::Unknown;
  return probabilityFromLogOdds(cell.logodds_nontrav) >= params.p_nontrav_threshold
             ? core::Label::NonTraversable
             : core::Label::Traversable;
}

float probabilityOf(const GridCell& cell, const GridParams& params) {
  return isKnown(cell, params) ? probabilityFromLogOdds(cell.logodds_nontrav) : GridCell::kNaN;
}

float probabilityNonTraversable(const TraversabilityGrid& grid, double x_m, double y_m) {
  const GridCell* c = grid.cellAt(x_m, y_m);
  return c != nullptr ? probabilityOf(*c, grid.params()) : GridCell::kNaN;
}

bool isKnown(const TraversabilityGrid& grid, double x_m, double y_m) {
  const GridCell* c = grid.cellAt(x_m, y_m);
  return c != nullptr && isKnown(*c, grid.params());
}

core::Label cellLabel(const TraversabilityGrid& grid, double x_m, double y_m) {
  const GridCell* c = grid.cellAt(x_m, y_m);
  return c != nullptr ? labelOf(*c, grid.params()) : core::Label::Unknown;
}

Eigen::MatrixXf layerMatrix(const TraversabilityGrid& grid, GridLayer layer) {
  Eigen::MatrixXf m(grid.sizeY(), grid.sizeX());
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    for (int cx = 0; cx < grid.sizeX(); ++cx) m(cy, cx) = layerValue(grid.at(cx, cy), layer);
  }
  return m;
}

GridStats computeStats(const TraversabilityGrid& grid) {
  GridStats s;
  s.cells = static_cast<std::size_t>(grid.sizeX()) * static_cast<std::size_t>(grid.sizeY());
  s.memory_bytes = grid.memoryBytes();
  for (int cy = 0; cy < grid.sizeY(); ++cy) {
    for (int cx = 0; cx < grid.sizeX(); ++cx) {
      switch (labelOf(grid.at(cx, cy), grid.params())) {
        case core::Label::Traversable:
          ++s.known;
          ++s.traversable;
          break;
        case core::Label::NonTraversable:
          ++s.known;
          ++s.non_traversable;
          break;
        case core::Label::Unknown: break;
      }
    }
  }
  return s;
}

}  // namespace upd::maps
