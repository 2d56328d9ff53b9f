#include "upd/core/classify.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace upd {

void ClassifyParams::validate() const {
  requireParam(zeta_min >= 0.0 && zeta_min <= 1.0, "ClassifyParams", "zeta_min", zeta_min,
               "must be in [0, 1]");
  requireParam(zeta_caution >= zeta_min && zeta_caution <= 1.0, "ClassifyParams",
               "zeta_caution", zeta_caution, "must be in [zeta_min, 1]");
  requireParam(max_slope_rad > 0 && max_slope_rad <= 0.5 * M_PI, "ClassifyParams",
               "max_slope_deg", max_slope_rad * kRadToDeg, "must be in (0, 90]");
  requireParam(min_neighbors >= 0, "ClassifyParams", "min_neighbors", min_neighbors,
               "must be >= 0");
}

Classification classify(const UpdResult& upd, const Eigen::Vector3f& up,
                        const ClassifyParams& params) {
  params.validate();
  const std::size_t n = upd.size();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  Classification out;
  out.label.assign(n, Label::Unknown);
  out.cost.assign(n, nan);
  out.slope_rad.assign(n, nan);
  const double zeta_span = params.zeta_caution - params.zeta_min;
  for (std::size_t i = 0; i < n; ++i) {
    if (!upd.isValid(i) || upd.k[i] < static_cast<std::uint32_t>(params.min_neighbors)) {
      ++out.unknown;
      continue;
    }
    const Eigen::Vector3f r = upd.r(i);
    const float norm = r.norm();
    // A vanishing r (normals cancelling) has no direction: treat it as the steepest slope.
    const double slope =
        norm > 0.f ? std::acos(std::clamp(static_cast<double>(r.dot(up) / norm), -1.0, 1.0))
                   : M_PI;
    out.slope_rad[i] = static_cast<float>(slope);
    const double zeta = upd.zeta[i];
    if (zeta < params.zeta_min || slope > params.max_slope_rad) {
      out.label[i] = Label::NonTraversable;
      out.cost[i] = 1.f;
      ++out.non_traversable;
      continue;
    }
    const double zeta_cost =
        zeta_span > 0 ? std::clamp((params.zeta_caution - zeta) / zeta_span, 0.0, 1.0) : 0.0;
    const double slope_ratio = slope / params.max_slope_rad;
    out.cost[i] = static_cast<float>(std::max(zeta_cost, slope_ratio * slope_ratio));
    out.label[i] = Label::Traversable;
    ++out.traversable;
  }
  return out;
}

const char* toString(Label l) {
  switch (l) {
    case Label::Traversable: return "traversable";
    case Label::NonTraversable: return "non_traversable";
    case Label::Unknown: return "unknown";
  }
  return "invalid";
}

}  // namespace upd
