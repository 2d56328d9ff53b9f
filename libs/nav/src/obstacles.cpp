#include "upd/nav/obstacles.h"

#include "upd/core/params.h"
#include "upd/maps/traversability_grid.h"

#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_set>

namespace upd::nav {

void ObstacleParams::validate() const {
  core::requireParam(std::isfinite(range_m) && range_m > 0, "ObstacleParams", "range_m", range_m,
               "must be > 0");
  core::requireParam(std::isfinite(decimation_m) && decimation_m > 0, "ObstacleParams", "decimation_m",
               decimation_m, "must be > 0");
  core::requireParam(std::isfinite(map_cell_border_range_m) && map_cell_border_range_m > 0,
                     "ObstacleParams", "map_cell_border_range_m", map_cell_border_range_m,
                     "must be > 0");
  core::requireParam(std::isfinite(point_height_m), "ObstacleParams", "point_height_m", point_height_m,
               "must be finite");
  core::requireParam(std::isfinite(unobserved_behind_m) && unobserved_behind_m >= 0,
                     "ObstacleParams", "unobserved_behind_m", unobserved_behind_m, "must be >= 0");
}

Eigen::Vector2d worldToRobot(const Pose2D& pose_world_robot, const Eigen::Vector2d& p_world) {
  const double c = std::cos(pose_world_robot.yaw_rad), s = std::sin(pose_world_robot.yaw_rad);
  const double dx = p_world.x() - pose_world_robot.x_m, dy = p_world.y() - pose_world_robot.y_m;
  return {c * dx + s * dy, -s * dx + c * dy};
}

Eigen::Vector2d robotToWorld(const Pose2D& pose_world_robot, const Eigen::Vector2d& p_robot) {
  const double c = std::cos(pose_world_robot.yaw_rad), s = std::sin(pose_world_robot.yaw_rad);
  return {pose_world_robot.x_m + c * p_robot.x() - s * p_robot.y(),
          pose_world_robot.y_m + s * p_robot.x() + c * p_robot.y()};
}

std::vector<Eigen::Vector2d> rectangleFence(const Eigen::Vector2d& min_xy,
                                            const Eigen::Vector2d& max_xy, double spacing_m) {
  if (!(spacing_m > 0) || !std::isfinite(spacing_m)) {
    throw std::invalid_argument("rectangleFence: spacing_m = " + std::to_string(spacing_m) +
                                ": must be > 0");
  }
  if (!(max_xy.x() > min_xy.x()) || !(max_xy.y() > min_xy.y())) {
    throw std::invalid_argument("rectangleFence: empty rectangle");
  }
  std::vector<Eigen::Vector2d> pts;
  const Eigen::Vector2d corners[4] = {
      min_xy, {max_xy.x(), min_xy.y()}, max_xy, {min_xy.x(), max_xy.y()}};
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector2d a = corners[k], b = corners[(k + 1) % 4];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing_m)));
    for (int i = 0; i < n; ++i) pts.push_back(a + (b - a) * (static_cast<double>(i) / n));
  }
  return pts;
}

ObstacleSource::ObstacleSource(const ObstacleParams& params) : params_(params) {
  params_.validate();
}

void ObstacleSource::setFrameObstacles(std::vector<Eigen::Vector2d> points_world) {
  frame_world_ = std::move(points_world);
}

void ObstacleSource::setFixedObstacles(std::vector<Eigen::Vector2d> points_world) {
  fixed_world_ = std::move(points_world);
}

void ObstacleSource::setUnobservedBehind(std::vector<Eigen::Vector2d> points_world) {
  unobserved_world_ = std::move(points_world);
}

namespace {

std::uint64_t squareKey(std::int64_t ix, std::int64_t iy) {
  return (static_cast<std::uint64_t>(ix) << 32) ^ (static_cast<std::uint64_t>(iy) & 0xffffffffull);
}

/// The key of the decimation square (edge 1 / inv_decimation_m) that holds p_world.
std::uint64_t decimationSquare(const Eigen::Vector2d& p_world, double inv_decimation_m) {
  return squareKey(static_cast<std::int64_t>(std::floor(p_world.x() * inv_decimation_m)),
                   static_cast<std::int64_t>(std::floor(p_world.y() * inv_decimation_m)));
}

}  // namespace

std::vector<Eigen::Vector2d> ObstacleSource::pointsInRobot(const Pose2D& pose_world_robot) const {
  const double r2 = params_.range_m * params_.range_m;
  const double inv = 1.0 / params_.decimation_m;
  const Eigen::Vector2d centre(pose_world_robot.x_m, pose_world_robot.y_m);
  std::unordered_set<std::uint64_t> taken;
  std::vector<Eigen::Vector2d> out;
  const auto inRange = [&](const Eigen::Vector2d& p_world) {
    return p_world.allFinite() && (p_world - centre).squaredNorm() <= r2;
  };
  if (params_.use_map && grid_ != nullptr) addMapPoints(pose_world_robot, taken, out);
  // One point per decimation square of the world frame: the first source that claims the
  // square gives its point (map cells first, so the set is stable from step to step).
  const auto add = [&](const Eigen::Vector2d& p_world) {
    if (!inRange(p_world) || !taken.insert(decimationSquare(p_world, inv)).second) return;
    out.push_back(worldToRobot(pose_world_robot, p_world));
  };
  if (params_.use_current_frame) {
    for (const auto& p : frame_world_) add(p);
  }
  for (const auto& p : fixed_world_) add(p);
  for (const auto& p : unobserved_world_) add(p);
  return out;
}

void ObstacleSource::addMapPoints(const Pose2D& pose_world_robot,
                                  std::unordered_set<std::uint64_t>& taken_squares,
                                  std::vector<Eigen::Vector2d>& out) const {
  const auto& g = *grid_;
  const double r = params_.range_m, inv = 1.0 / params_.decimation_m;
  const Eigen::Vector2d centre(pose_world_robot.x_m, pose_world_robot.y_m);
  int cx0, cy0, cx1, cy1;
  // Clamp the search square to the window; cellIndex fails outside it.
  const double x0 = std::max(centre.x() - r, g.xMin() + 0.5 * g.cellSize());
  const double y0 = std::max(centre.y() - r, g.yMin() + 0.5 * g.cellSize());
  const double x1 = std::min(centre.x() + r, g.xMax() - 0.5 * g.cellSize());
  const double y1 = std::min(centre.y() + r, g.yMax() - 0.5 * g.cellSize());
  if (!(x0 <= x1 && y0 <= y1 && g.cellIndex(x0, y0, cx0, cy0) && g.cellIndex(x1, y1, cx1, cy1))) {
    return;
  }
  // The points of a cell sit on a lattice of half cells (k = 2 cx + 1 + i): a border shared by
  // two cells gives its points once, whatever the rounding of the cell centres. The map's points
  // claim their decimation squares against the other sources but are not thinned among
  // themselves: at the default 5 cm decimation a 10 cm cell would keep only two per side.
  std::unordered_set<std::uint64_t> lattice;
  const double h = 0.5 * g.cellSize();
  const int reach = params_.map_cell_border ? 1 : 0;
  const double r2 = r * r;
  const auto addCell = [&](int cx, int cy) {
    const Eigen::Vector2d c = g.cellCenter(cx, cy);
    const int k = (c - centre).norm() < params_.map_cell_border_range_m ? reach : 0;
    for (int j = -k; j <= k; ++j) {
      for (int i = -k; i <= k; ++i) {
        const Eigen::Vector2d p = c + Eigen::Vector2d(i * h, j * h);
        if ((p - centre).squaredNorm() > r2) continue;
        if (!lattice.insert(squareKey(2 * cx + 1 + i, 2 * cy + 1 + j)).second) continue;
        taken_squares.insert(decimationSquare(p, inv));
        out.push_back(worldToRobot(pose_world_robot, p));
      }
    }
  };
  for (int cy = cy0; cy <= cy1; ++cy) {
    for (int cx = cx0; cx <= cx1; ++cx) {
      if (maps::labelOf(g.at(cx, cy), g.params()) == core::Label::NonTraversable) addCell(cx, cy);
    }
  }
}

}  // namespace upd::nav
