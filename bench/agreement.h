// Agreement of a fast result with the exact path on the same cloud: exact normals for every
// point, the exact UPD (computeUpd's sums, eqs. 6-8) for every finite point or an evenly spaced
// sample of them, and the labels both give.
#pragma once

#include <cstddef>
#include <vector>

#include "report.h"
#include "upd/core/classify.h"
#include "upd/core/pipeline.h"
#include "upd/core/upd.h"

namespace upd::bench {

struct ExactReference {
  std::vector<std::size_t> index;  // the compared points (all finite points, or a sample)
  core::UpdResult upd;                   // exact UPD at those points
  core::Classification classes;
  double normals_ms = 0, upd_ms = 0;
  std::size_t finite = 0;
};

/// Exact normals for every point; the exact UPD for every finite point when that is
/// affordable, else for max_samples evenly spaced finite points.
ExactReference exactReference(const core::PointCloud& cloud, const core::PipelineParams& params,
                              std::size_t max_samples);

struct Agreement {
  std::size_t compared = 0, finite = 0, both_valid = 0, validity_differs = 0;
  double mean_abs_dzeta = kNaN, max_abs_dzeta = kNaN, same_label = kNaN;
  double exact_normals_ms = kNaN, exact_upd_ms = kNaN;
  bool met() const {
    return std::isfinite(mean_abs_dzeta) && mean_abs_dzeta <= kMaxMeanDzeta &&
           same_label >= kMinSameLabel;
  }
  json toJson() const;
};

/// Compares the UPD of the reference's points in `fast` (any method) with the exact reference.
Agreement agreement(const ExactReference& ref, const core::UpdResult& fast,
                    const core::PipelineParams& params);

}  // namespace upd::bench
