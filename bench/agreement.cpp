#include "agreement.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "upd/core/kdtree.h"
#include "upd/core/normals.h"
#include "upd/core/stopwatch.h"

namespace core = upd::core;

namespace upd::bench {
namespace {

// computeUpd's loop, for the sampled points of ref only.
void exactUpdAtSamples(const core::PointCloud& cloud, const core::KdTree& tree, const core::Normals& normals,
                       const core::UpdParams& params, ExactReference& ref) {
  const std::size_t n = ref.index.size();
  const auto radius = static_cast<float>(params.radius_m);
#pragma omp parallel
  {
    std::vector<std::uint32_t> nb;
#pragma omp for schedule(dynamic, 8)
    for (std::ptrdiff_t qq = 0; qq < static_cast<std::ptrdiff_t>(n); ++qq) {
      const auto q = static_cast<std::size_t>(qq);
      tree.radiusSearch(cloud.point(ref.index[q]), radius, nb);
      double sx = 0, sy = 0, sz = 0;
      std::uint32_t k = 0;
      for (const std::uint32_t j : nb) {
        if (!normals.isValid(j)) continue;
        sx += normals.nx[j], sy += normals.ny[j], sz += normals.nz[j];
        ++k;
      }
      if (k < static_cast<std::uint32_t>(params.min_neighbors)) continue;
      ref.upd.rx[q] = static_cast<float>(sx);
      ref.upd.ry[q] = static_cast<float>(sy);
      ref.upd.rz[q] = static_cast<float>(sz);
      ref.upd.zeta[q] = static_cast<float>(std::sqrt(sx * sx + sy * sy + sz * sz) / k);
      ref.upd.k[q] = k;
    }
  }
}

}  // namespace

ExactReference exactReference(const core::PointCloud& cloud, const core::PipelineParams& params,
                              std::size_t max_samples) {
  ExactReference ref;
  const Eigen::Vector3f up = params.unitUp();
  core::Stopwatch watch;
  const core::KdTree tree(cloud);
  const core::Normals normals = core::computeNormals(cloud, tree, params.normals, up);
  ref.normals_ms = watch.elapsedMs();
  std::vector<std::size_t> finite;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.isFinite(i)) finite.push_back(i);
  }
  ref.finite = finite.size();
  const std::size_t stride =
      std::max<std::size_t>(1, (finite.size() + max_samples - 1) / max_samples);
  for (std::size_t j = 0; j < finite.size(); j += stride) ref.index.push_back(finite[j]);
  const std::size_t n = ref.index.size();
  ref.upd = core::UpdResult::unscored(n);
  watch.restart();
  if (stride == 1) {
    const core::UpdResult all = core::computeUpd(cloud, tree, normals, params.upd);
    for (std::size_t q = 0; q < n; ++q) {
      const std::size_t i = ref.index[q];
      ref.upd.rx[q] = all.rx[i], ref.upd.ry[q] = all.ry[i], ref.upd.rz[q] = all.rz[i];
      ref.upd.zeta[q] = all.zeta[i], ref.upd.k[q] = all.k[i];
    }
  } else {
    exactUpdAtSamples(cloud, tree, normals, params.upd, ref);
  }
  for (std::size_t q = 0; q < n; ++q) ref.upd.invalid += ref.upd.isValid(q) ? 0 : 1;
  ref.upd_ms = watch.elapsedMs();
  ref.classes = core::classify(ref.upd, up, params.classify);
  return ref;
}

json Agreement::toJson() const {
  return {{"points_compared", compared},
          {"finite_points", finite},
          {"sampled", compared < finite},
          {"both_scored", both_valid},
          {"scored_by_one_only", validity_differs},
          {"mean_abs_dzeta", num(mean_abs_dzeta)},
          {"max_abs_dzeta", num(max_abs_dzeta)},
          {"same_label_fraction", num(same_label)},
          {"exact_normals_ms", num(exact_normals_ms)},
          {"exact_upd_ms", num(exact_upd_ms)},
          {"met", met()}};
}

Agreement agreement(const ExactReference& ref, const core::UpdResult& fast,
                    const core::PipelineParams& params) {
  Agreement a;
  a.compared = ref.index.size();
  a.finite = ref.finite;
  a.exact_normals_ms = ref.normals_ms;
  a.exact_upd_ms = ref.upd_ms;
  core::UpdResult sub;
  const std::size_t n = ref.index.size();
  sub.rx.resize(n), sub.ry.resize(n), sub.rz.resize(n), sub.zeta.resize(n), sub.k.resize(n);
  for (std::size_t q = 0; q < n; ++q) {
    const std::size_t i = ref.index[q];
    sub.rx[q] = fast.rx[i], sub.ry[q] = fast.ry[i], sub.rz[q] = fast.rz[i];
    sub.zeta[q] = fast.zeta[i], sub.k[q] = fast.k[i];
  }
  const core::Classification cls = core::classify(sub, params.unitUp(), params.classify);
  double sum = 0, worst = 0;
  std::size_t same = 0;
  for (std::size_t q = 0; q < n; ++q) {
    same += cls.label[q] == ref.classes.label[q] ? 1 : 0;
    const bool ve = ref.upd.isValid(q), vf = sub.isValid(q);
    if (ve != vf) ++a.validity_differs;
    if (!ve || !vf) continue;
    const double d = std::abs(static_cast<double>(ref.upd.zeta[q]) - sub.zeta[q]);
    sum += d;
    worst = std::max(worst, d);
    ++a.both_valid;
  }
  if (a.both_valid > 0) {
    a.mean_abs_dzeta = sum / static_cast<double>(a.both_valid);
    a.max_abs_dzeta = worst;
  }
  if (n > 0) a.same_label = static_cast<double>(same) / static_cast<double>(n);
  return a;
}

}  // namespace upd::bench
