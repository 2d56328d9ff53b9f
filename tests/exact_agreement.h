// The fast UPD against the exact path at sampled points: eq. 6 summed over a k-d tree radius
// search from the exact normals, labels by classify with default parameters. Shared by the
// agreement tests on generated scenes (tests/core) and on real frames (tests/apps).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "upd/core/classify.h"
#include "upd/core/kdtree.h"
#include "upd/core/normals.h"
#include "upd/core/point_cloud.h"
#include "upd/core/upd.h"

namespace upd::test {

struct Agreement {
  std::size_t compared = 0, both_valid = 0, validity_differs = 0, same_label = 0;
  double mean_abs_dzeta = 0, max_abs_dzeta = 0;
  double sameLabelFraction() const {
    return compared ? static_cast<double>(same_label) / static_cast<double>(compared) : 0.0;
  }
};

// The exact UPD (computeUpd's sums) at every stride-th finite point, from exact normals, against
// the fast UPD at the same points; labels by classify with default parameters.
inline Agreement agreeWithExact(const core::PointCloud& cloud, const core::Normals& exact_normals,
                                const core::UpdResult& fast, const core::UpdParams& p,
                                const Eigen::Vector3f& up, std::size_t stride) {
  const core::KdTree tree(cloud);
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.isFinite(i) && (i % stride) == 0) idx.push_back(i);
  }
  const float nan = std::numeric_limits<float>::quiet_NaN();
  core::UpdResult e, f;
  for (core::UpdResult* r : {&e, &f}) {
    r->rx.assign(idx.size(), nan);
    r->ry = r->rz = r->zeta = r->rx;
    r->k.assign(idx.size(), 0);
  }
  std::vector<std::uint32_t> nb;
  for (std::size_t q = 0; q < idx.size(); ++q) {
    tree.radiusSearch(cloud.point(idx[q]), static_cast<float>(p.radius_m), nb);
    double x = 0, y = 0, z = 0;
    std::uint32_t k = 0;
    for (const auto j : nb) {
      if (!exact_normals.isValid(j)) continue;
      x += exact_normals.nx[j], y += exact_normals.ny[j], z += exact_normals.nz[j];
      ++k;
    }
    if (k >= static_cast<std::uint32_t>(p.min_neighbors)) {
      e.rx[q] = static_cast<float>(x), e.ry[q] = static_cast<float>(y);
      e.rz[q] = static_cast<float>(z), e.k[q] = k;
      e.zeta[q] = static_cast<float>(std::sqrt(x * x + y * y + z * z) / k);
    }
    const std::size_t i = idx[q];
    f.rx[q] = fast.rx[i], f.ry[q] = fast.ry[i], f.rz[q] = fast.rz[i];
    f.zeta[q] = fast.zeta[i], f.k[q] = fast.k[i];
  }
  const core::Classification ce = core::classify(e, up, core::ClassifyParams{});
  const core::Classification cf = core::classify(f, up, core::ClassifyParams{});
  Agreement a;
  a.compared = idx.size();
  for (std::size_t q = 0; q < idx.size(); ++q) {
    a.same_label += ce.label[q] == cf.label[q] ? 1 : 0;
    if (e.isValid(q) != f.isValid(q)) ++a.validity_differs;
    if (!e.isValid(q) || !f.isValid(q)) continue;
    const double d = std::abs(static_cast<double>(e.zeta[q]) - f.zeta[q]);
    a.mean_abs_dzeta += d;
    a.max_abs_dzeta = std::max(a.max_abs_dzeta, d);
    ++a.both_valid;
  }
  if (a.both_valid) a.mean_abs_dzeta /= static_cast<double>(a.both_valid);
  return a;
}

}  // namespace upd::test
