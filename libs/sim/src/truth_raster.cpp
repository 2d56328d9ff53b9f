#include "upd/sim/truth_raster.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace upd::sim {

TruthRaster::TruthRaster(const Terrain& terrain, double cell_m)
    : min_xy_(terrain.minXY()), cell_m_(cell_m) {
  if (!(cell_m > 0) || !std::isfinite(cell_m)) {
    throw std::invalid_argument("TruthRaster: cell_m = " + std::to_string(cell_m) +
                                ": must be > 0");
  }
  const Eigen::Vector2d ext = terrain.maxXY() - terrain.minXY();
  nx_ = std::max(1, static_cast<int>(std::ceil(ext.x() / cell_m)));
  ny_ = std::max(1, static_cast<int>(std::ceil(ext.y() / cell_m)));
  labels_.resize(static_cast<std::size_t>(nx_) * ny_);
  for (int iy = 0; iy < ny_; ++iy) {
    for (int ix = 0; ix < nx_; ++ix) {
      const Eigen::Vector2d c = cellCenter(ix, iy);
      labels_[static_cast<std::size_t>(iy) * nx_ + ix] = terrain.truthAt(c.x(), c.y());
    }
  }
}

Eigen::Vector2d TruthRaster::cellCenter(int ix, int iy) const {
  return min_xy_ + Eigen::Vector2d((ix + 0.5) * cell_m_, (iy + 0.5) * cell_m_);
}

namespace {

// Distance from a world point to the footprint rectangle of the robot at pose (0 inside).
double distanceToFootprint(const Eigen::Vector3d& pose, const Eigen::Vector2d& p_world,
                           const RobotBodyParams& body) {
  const double c = std::cos(pose.z()), s = std::sin(pose.z());
  const double dx = p_world.x() - pose.x(), dy = p_world.y() - pose.y();
  const double u = c * dx + s * dy, v = -s * dx + c * dy;  // in the robot frame
  const double ou = std::max(0.0, std::abs(u) - 0.5 * body.length_m);
  const double ov = std::max(0.0, std::abs(v) - 0.5 * body.width_m);
  return std::hypot(ou, ov);
}

}  // namespace

double TruthRaster::clearance(const Eigen::Vector3d& pose, const RobotBodyParams& body,
                              double search_m) const {
  const double reach = 0.5 * std::hypot(body.length_m, body.width_m) + search_m;
  const auto cell = [&](double v, double lo) {
    return static_cast<int>(std::floor((v - lo) / cell_m_));
  };
  const int ix0 = std::max(0, cell(pose.x() - reach, min_xy_.x()));
  const int iy0 = std::max(0, cell(pose.y() - reach, min_xy_.y()));
  const int ix1 = std::min(nx_ - 1, cell(pose.x() + reach, min_xy_.x()));
  const int iy1 = std::min(ny_ - 1, cell(pose.y() + reach, min_xy_.y()));
  double best = search_m;
  for (int iy = iy0; iy <= iy1; ++iy) {
    for (int ix = ix0; ix <= ix1; ++ix) {
      if (at(ix, iy) != core::Label::NonTraversable) continue;
      best = std::min(best, distanceToFootprint(pose, cellCenter(ix, iy), body));
    }
  }
  return best;
}

bool TruthRaster::collides(const Eigen::Vector3d& pose, const RobotBodyParams& body) const {
  return clearance(pose, body, cell_m_) <= 0.0;
}

}  // namespace upd::sim
