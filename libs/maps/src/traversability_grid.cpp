#include "upd/maps/traversability_grid.h"

#include "upd/maps/fusion.h"

#include <mrpt/containers/CDynamicGrid.h>

#include <cassert>
#include <cmath>
#include <stdexcept>
#include <string>

namespace upd::maps {

namespace {
// Larger windows would not fit a 32-bit cell index (and would not fit in memory anyway).
constexpr double kMaxCellsPerSide = 46000;
}  // namespace

void GridParams::validate() const {
  core::requireParam(std::isfinite(cell_size_m) && cell_size_m > 0, "GridParams", "cell_size_m",
               cell_size_m, "must be > 0");
  core::requireParam(std::isfinite(extent_m) && extent_m >= 2 * cell_size_m, "GridParams", "extent_m",
               extent_m, "must be at least two cells");
  core::requireParam(extent_m / cell_size_m <= kMaxCellsPerSide, "GridParams", "extent_m", extent_m,
               "gives more than 46000 cells per side (raise cell_size_m)");
  core::requireParam(std::isfinite(center_x_m), "GridParams", "center_x_m", center_x_m, "must be finite");
  core::requireParam(std::isfinite(center_y_m), "GridParams", "center_y_m", center_y_m, "must be finite");
  core::requireParam(recenter_fraction > 0 && recenter_fraction < 0.5, "GridParams", "recenter_fraction",
               recenter_fraction, "must be in (0, 0.5)");
  core::requireParam(p_nontrav_threshold > 0 && p_nontrav_threshold < 1, "GridParams",
               "p_nontrav_threshold", p_nontrav_threshold, "must be in (0, 1)");
  core::requireParam(min_hits_known >= 1, "GridParams", "min_hits_known", min_hits_known, "must be >= 1");
}

int GridParams::cellsPerSide() const {
  return static_cast<int>(std::lround(extent_m / cell_size_m));
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
  int n = 0;                    // cells per side

  void allocate(double cell_size_m) {
    const GridCell unknown;
    cells.setSize(static_cast<double>(i0) * cell_size_m, static_cast<double>(i0 + n) * cell_size_m,
                  static_cast<double>(j0) * cell_size_m, static_cast<double>(j0 + n) * cell_size_m,
                  cell_size_m, &unknown);
    if (cells.getSizeX() != static_cast<std::size_t>(n) ||
        cells.getSizeY() != static_cast<std::size_t>(n)) {
      throw std::logic_error("TraversabilityGrid: CDynamicGrid allocated " +
                             std::to_string(cells.getSizeX()) + " x " +
                             std::to_string(cells.getSizeY()) + " cells instead of " +
                             std::to_string(n) + " x " + std::to_string(n));
    }
  }
  GridCell& at(int cx, int cy) { return *cells.cellByIndex(cx, cy); }
};

TraversabilityGrid::TraversabilityGrid(const GridParams& params)
    : params_(params), impl_(std::make_unique<Impl>()) {
  params_.validate();
  impl_->n = params_.cellsPerSide();
  impl_->i0 = static_cast<std::int64_t>(std::floor(params_.center_x_m / params_.cell_size_m)) -
              impl_->n / 2;
  impl_->j0 = static_cast<std::int64_t>(std::floor(params_.center_y_m / params_.cell_size_m)) -
              impl_->n / 2;
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

int TraversabilityGrid::sizeX() const { return impl_->n; }
int TraversabilityGrid::sizeY() const { return impl_->n; }
std::int64_t TraversabilityGrid::originI() const { return impl_->i0; }
std::int64_t TraversabilityGrid::originJ() const { return impl_->j0; }
double TraversabilityGrid::xMin() const { return static_cast<double>(impl_->i0) * cellSize(); }
double TraversabilityGrid::yMin() const { return static_cast<double>(impl_->j0) * cellSize(); }
double TraversabilityGrid::xMax() const {
  return static_cast<double>(impl_->i0 + impl_->n) * cellSize();
}
double TraversabilityGrid::yMax() const {
  return static_cast<double>(impl_->j0 + impl_->n) * cellSize();
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
  ix.size_x = impl_->n;
  ix.size_y = impl_->n;
  return ix;
}

Eigen::Vector2d TraversabilityGrid::cellCenter(int cx, int cy) const {
  return {(static_cast<double>(impl_->i0 + cx) + 0.5) * cellSize(),
          (static_cast<double>(impl_->j0 + cy) + 0.5) * cellSize()};
}

const GridCell& TraversabilityGrid::at(int cx, int cy) const {
  assert(cx >= 0 && cx < impl_->n && cy >= 0 && cy < impl_->n);
  return *impl_->cells.cellByIndex(static_cast<unsigned>(cx), static_cast<unsigned>(cy));
}
GridCell& TraversabilityGrid::at(int cx, int cy) {
  assert(cx >= 0 && cx < impl_->n && cy >= 0 && cy < impl_->n);
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
  core::requireParam(robot_xy.allFinite(), "TraversabilityGrid::moveTo", "robot_xy",
               std::to_string(robot_xy.x()) + "," + std::to_string(robot_xy.y()), "must be finite");
  const double ri = std::floor(robot_xy.x() / cellSize());
  const double rj = std::floor(robot_xy.y() / cellSize());
  const int n = impl_->n;
  const double half = n / 2;
  const double limit = params_.recenter_fraction * n;
  if (std::abs(ri - (static_cast<double>(impl_->i0) + half)) <= limit &&
      std::abs(rj - (static_cast<double>(impl_->j0) + half)) <= limit) {
    return false;
  }
  auto moved = std::make_unique<Impl>();
  moved->n = n;
  moved->i0 = static_cast<std::int64_t>(ri) - n / 2;
  moved->j0 = static_cast<std::int64_t>(rj) - n / 2;
  moved->allocate(cellSize());
  // Copy the overlap, cell by world index: cells move whole, nothing is resampled.
  const std::int64_t gi_begin = std::max(impl_->i0, moved->i0);
  const std::int64_t gi_end = std::min(impl_->i0 + n, moved->i0 + n);
  const std::int64_t gj_begin = std::max(impl_->j0, moved->j0);
  const std::int64_t gj_end = std::min(impl_->j0 + n, moved->j0 + n);
  for (std::int64_t gj = gj_begin; gj < gj_end; ++gj) {
    for (std::int64_t gi = gi_begin; gi < gi_end; ++gi) {
      moved->at(static_cast<int>(gi - moved->i0), static_cast<int>(gj - moved->j0)) =
          impl_->at(static_cast<int>(gi - impl_->i0), static_cast<int>(gj - impl_->j0));
    }
  }
  impl_ = std::move(moved);
  return true;
}

void TraversabilityGrid::clear() { impl_->cells.fill(GridCell{}); }

std::size_t TraversabilityGrid::memoryBytes() const {
  return sizeof(Impl) + impl_->cells.data().capacity() * sizeof(GridCell);
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
