// The JSON run summary: what a pipeline run produced (counts, zeta statistics and histogram,
// label counts, stage timings, pre-processing statistics) and the exact parameters it used, so
// a result file can be reproduced and compared. `upd analyze --json` writes it.
//
// Non-finite numbers are never written: a statistic that does not exist (zeta of an empty
// result) is null.
#pragma once

#include "upd/core/pipeline.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace upd::io {

/// The zeta histogram's range: zeta of a well-sampled surface lies in [sqrt(2)/2, 1]
/// (paper eq. 8); the lower edge leaves a small margin below sqrt(2)/2. Values outside the
/// range are counted in the end bins.
constexpr double kZetaHistogramMin = 0.70;
constexpr double kZetaHistogramMax = 1.0;
constexpr int kZetaHistogramBins = 20;

/// {"edges": [bins + 1 values], "counts": [bins values]} of the finite values; values below
/// lo or above hi are clamped into the first or last bin. Throws std::invalid_argument unless
/// bins > 0 and lo < hi.
nlohmann::json histogramJson(const std::vector<float>& values, double lo, double hi, int bins);

/// Every parameter of params, by the keys of the structs' visit() (angles in degrees under
/// their `_deg` keys): {"up": [x, y, z], "preprocess": {...}, "normals": {...}, "upd": {...},
/// "classify": {...}}.
nlohmann::json paramsJson(const core::PipelineParams& params);

/// The run summary. points_in is the size of the cloud given to runPipeline. Keys:
/// points_in, points_scored (finite zeta), points_invalid (scored-cloud points with NaN zeta
/// plus non-finite input points dropped by pre-processing), points_after_preprocess, radius_m,
/// zeta {min, mean, max, histogram {edges, counts}}, labels {traversable, non_traversable,
/// unknown}, timing_ms {preprocess, index, normals, upd, classify, total}, preprocess {the
/// PreprocessStats counters}, normals_invalid, params (paramsJson).
nlohmann::json summaryJson(const core::PipelineResult& result, const core::PipelineParams& params,
                           std::size_t points_in);

/// Writes j (indented, newline-terminated) through writeFileAtomically.
void writeJsonAtomically(const std::string& path, const nlohmann::json& j);

}  // namespace upd::io
