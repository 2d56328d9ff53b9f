#include "upd/maps/fusion.h"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace upd::maps {

void PointsWorld::validate() const {
  if (size == 0) return;
  auto need = [](const void* p, const char* field) {
    if (p == nullptr) {
      throw std::invalid_argument(std::string("PointsWorld.") + field +
                                  " is null but size > 0: x, y, z and label are required");
    }
  };
  need(x, "x");
  need(y, "y");
  need(z, "z");
  need(label, "label");
}

PointsWorld viewPoints(const core::PointCloud& cloud_world, const core::Classification& classes,
                       const core::UpdResult* upd) {
  const std::size_t n = cloud_world.size();
  core::requireParam(classes.label.size() == n, "viewPoints", "classes.label.size()",
               classes.label.size(), "must equal the cloud's size");
  core::requireParam(classes.slope_rad.empty() || classes.slope_rad.size() == n, "viewPoints",
               "classes.slope_rad.size()", classes.slope_rad.size(),
               "must be 0 or the cloud's size");
  core::requireParam(classes.cost.empty() || classes.cost.size() == n, "viewPoints",
               "classes.cost.size()", classes.cost.size(), "must be 0 or the cloud's size");
  if (upd != nullptr) {
    core::requireParam(upd->zeta.size() == n, "viewPoints", "upd.zeta.size()", upd->zeta.size(),
                 "must equal the cloud's size");
  }
  PointsWorld v;
  v.size = n;
  if (n == 0) return v;
  v.x = cloud_world.x.data();
  v.y = cloud_world.y.data();
  v.z = cloud_world.z.data();
  v.label = classes.label.data();
  v.slope_rad = classes.slope_rad.empty() ? nullptr : classes.slope_rad.data();
  v.cost = classes.cost.empty() ? nullptr : classes.cost.data();
  v.zeta = upd != nullptr ? upd->zeta.data() : nullptr;
  return v;
}

void FusionParams::validate() const {
  core::requireParam(std::isfinite(logodds_hit) && logodds_hit > 0, "FusionParams", "logodds_hit",
               logodds_hit, "must be > 0");
  core::requireParam(std::isfinite(logodds_miss) && logodds_miss < 0, "FusionParams", "logodds_miss",
               logodds_miss, "must be < 0");
  core::requireParam(std::isfinite(logodds_min) && logodds_min < 0, "FusionParams", "logodds_min",
               logodds_min, "must be < 0");
  core::requireParam(std::isfinite(logodds_max) && logodds_max > 0, "FusionParams", "logodds_max",
               logodds_max, "must be > 0");
  core::requireParam(nontrav_fraction > 0 && nontrav_fraction <= 1, "FusionParams", "nontrav_fraction",
               nontrav_fraction, "must be in (0, 1]");
  core::requireParam(min_points_per_cell >= 1, "FusionParams", "min_points_per_cell", min_points_per_cell,
               "must be >= 1");
}

double frameLogOddsUpdate(std::size_t n_nontraversable, std::size_t n_traversable,
                          const FusionParams& params) {
  const std::size_t n = n_nontraversable + n_traversable;
  if (n == 0 || n < static_cast<std::size_t>(params.min_points_per_cell)) return 0.0;
  // The tolerance keeps e.g. 3 of 10 points at nontrav_fraction 0.3 a hit despite rounding.
  const bool hit = static_cast<double>(n_nontraversable) >=
                   params.nontrav_fraction * static_cast<double>(n) - 1e-9;
  return hit ? params.logodds_hit : params.logodds_miss;
}

float fuseLogOdds(float logodds, double update, const FusionParams& params) {
  const double prior = std::isnan(logodds) ? 0.0 : static_cast<double>(logodds);
  return static_cast<float>(std::clamp(prior + update, params.logodds_min, params.logodds_max));
}

}  // namespace upd::maps
