#include "upd/io/json_io.h"
#include "upd/core/version.h"

#include "upd/io/atomic_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <utility>

namespace upd::io {

namespace {

using nlohmann::json;

/// A float as the double with the same shortest decimal form, so 0.1f is written as 0.1 and
/// not 0.10000000149011612. Non-finite values become null.
json floatValue(float f) {
  if (!std::isfinite(f)) return nullptr;
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf - 1, f);
  *r.ptr = '\0';
  return std::strtod(buf, nullptr);
}

json doubleValue(double d) {
  if (!std::isfinite(d)) return nullptr;
  return d;
}

/// Collects a params struct's fields through its visit(); the generic overload covers any
/// further field type a struct may add (as long as nlohmann can serialize it).
struct JsonParamVisitor {
  json& out;

  void operator()(const char* key, double& v, const char* /*doc*/) { out[key] = doubleValue(v); }
  void operator()(const char* key, float& v, const char* /*doc*/) { out[key] = floatValue(v); }
  void operator()(const char* key, int& v, const char* /*doc*/) { out[key] = v; }
  void operator()(const char* key, bool& v, const char* /*doc*/) { out[key] = v; }
  void operator()(const char* key, Eigen::Vector3f& v, const char* /*doc*/) {
    out[key] = json::array({floatValue(v.x()), floatValue(v.y()), floatValue(v.z())});
  }
  template <class T>
  void operator()(const char* key, T& v, const char* /*doc*/) {
    out[key] = v;
  }
  void angleDeg(const char* key, double& radians, const char* /*doc*/) {
    out[key] = doubleValue(radians * core::kRadToDeg);
  }
  /// Enums by their ini name, so the params can be copied back into an ini file.
  template <class E, std::size_t N>
  void choice(const char* key, E& value, const core::EnumName<E> (&names)[N], const char* /*doc*/) {
    const char* name = core::enumName(names, value);
    out[key] = name != nullptr ? json(name) : json(static_cast<int>(value));
  }
};

template <class P>
json visitToJson(P p) {  // by value: visit() is non-const because loaders write through it
  json j = json::object();
  JsonParamVisitor v{j};
  p.visit(v);
  return j;
}

}  // namespace

json histogramJson(const std::vector<float>& values, double lo, double hi, int bins) {
  if (bins <= 0) throw std::invalid_argument("histogramJson: bins must be > 0");
  if (!(lo < hi)) throw std::invalid_argument("histogramJson: need lo < hi");
  const double width = (hi - lo) / bins;
  json edges = json::array();
  for (int i = 0; i <= bins; ++i) {
    // Rounded to 1e-9 so edges print as 0.715, not 0.7150000000000001.
    edges.push_back(std::round((lo + i * width) * 1e9) / 1e9);
  }
  std::vector<std::size_t> counts(static_cast<std::size_t>(bins), 0);
  for (float v : values) {
    if (!std::isfinite(v)) continue;
    const double bin = std::floor((v - lo) / width);
    const int b = static_cast<int>(std::clamp(bin, 0.0, static_cast<double>(bins - 1)));
    ++counts[static_cast<std::size_t>(b)];
  }
  return json{{"edges", edges}, {"counts", counts}};
}

json paramsJson(const core::PipelineParams& params) {
  json j = json::object();
  j["up"] = json::array(
      {floatValue(params.up.x()), floatValue(params.up.y()), floatValue(params.up.z())});
  j["preprocess"] = visitToJson(params.preprocess);
  j["normals"] = visitToJson(params.normals);
  j["upd"] = visitToJson(params.upd);
  j["classify"] = visitToJson(params.classify);
  return j;
}

namespace {

/// {min, mean, max, histogram} of the finite zeta values (null statistics when there are none);
/// scored receives their number.
json zetaJson(const std::vector<float>& zeta, std::size_t& scored) {
  scored = 0;
  double sum = 0.0;
  float zmin = std::numeric_limits<float>::infinity();
  float zmax = -std::numeric_limits<float>::infinity();
  for (float z : zeta) {
    if (!std::isfinite(z)) continue;
    ++scored;
    sum += z;
    zmin = std::min(zmin, z);
    zmax = std::max(zmax, z);
  }
  json z = json::object();
  z["min"] = scored ? floatValue(zmin) : json(nullptr);
  z["mean"] = scored ? doubleValue(sum / static_cast<double>(scored)) : json(nullptr);
  z["max"] = scored ? floatValue(zmax) : json(nullptr);
  z["histogram"] =
      histogramJson(zeta, kZetaHistogramMin, kZetaHistogramMax, kZetaHistogramBins);
  return z;
}

/// Non-finite input points that pre-processing dropped. PreprocessStats.non_finite counts the
/// non-finite input points; those still in the scored cloud are already among the unscored.
std::size_t droppedNonFinite(const core::PipelineResult& result) {
  std::size_t kept_non_finite = 0;
  for (std::size_t i = 0; i < result.cloud.size(); ++i) {
    kept_non_finite += result.cloud.isFinite(i) ? 0 : 1;
  }
  const std::size_t non_finite = result.preprocess_stats.non_finite;
  return non_finite > kept_non_finite ? non_finite - kept_non_finite : 0;
}

json labelsJson(const std::vector<core::Label>& labels) {
  std::size_t traversable = 0, non_traversable = 0, unknown = 0;
  for (core::Label l : labels) {
    switch (l) {
      case core::Label::Traversable: ++traversable; break;
      case core::Label::NonTraversable: ++non_traversable; break;
      case core::Label::Unknown: ++unknown; break;
    }
  }
  return {{"traversable", traversable},
          {"non_traversable", non_traversable},
          {"unknown", unknown}};
}

/// Which path scored the cloud (UpdParams::method auto lets the pipeline choose), into j.
void addMethod(json& j, const core::PipelineResult& result, const core::PipelineParams& params) {
  j["method"] = result.method == core::UpdMethod::Fast ? "fast" : "exact";
  j["normals_method"] = result.method == core::UpdMethod::Exact ? "exact (k-d tree)"
                        : result.organized_normals        ? "organized window scans"
                                                          : "hash grid";
  if (result.method == core::UpdMethod::Fast) {
    // The points near zeta_min that got the exact sums (UpdParams::fast_exact_band).
    j["exact_band"] = {{"band", doubleValue(params.upd.fast_exact_band)},
                       {"zeta_min", doubleValue(params.classify.zeta_min)},
                       {"points", result.exact_band_points}};
    // The lattice used: fast_cells_per_radius, or finer on a dense cloud (fast_cells_per_point).
    j["lattice_cells_per_radius"] = result.fast_cells_per_radius;
  }
}

json timingJson(const core::StageTimings& t) {
  return {{"preprocess", doubleValue(t.preprocess_ms)}, {"index", doubleValue(t.index_ms)},
          {"normals", doubleValue(t.normals_ms)},       {"upd", doubleValue(t.upd_ms)},
          {"classify", doubleValue(t.classify_ms)},     {"total", doubleValue(t.total_ms)}};
}

json preprocessJson(const core::PreprocessStats& s) {
  return {{"points_in", s.points_in},
          {"non_finite", s.non_finite},
          {"range_removed", s.range_removed},
          {"after_voxel", s.after_voxel},
          {"outliers_removed", s.outliers_removed},
          {"points_out", s.points_out}};
}

}  // namespace

json summaryJson(const core::PipelineResult& result, const core::PipelineParams& params,
                 std::size_t points_in) {
  std::size_t scored = 0;
  json z = zetaJson(result.upd.zeta, scored);
  // Scored-cloud points without a zeta, including points scored while non-finite (when
  // pre-processing kept them). zeta may be shorter than the cloud if a stage did not run.
  const std::size_t cloud_n = result.cloud.size();
  const std::size_t unscored = cloud_n > scored ? cloud_n - scored : 0;

  json j = json::object();
  j["points_in"] = points_in;
  j["points_scored"] = scored;
  j["points_invalid"] = unscored + droppedNonFinite(result);
  j["points_after_preprocess"] = cloud_n;
  j["radius_m"] = doubleValue(params.upd.radius_m);
  addMethod(j, result, params);
  j["zeta"] = std::move(z);
  j["labels"] = labelsJson(result.classes.label);
  j["timing_ms"] = timingJson(result.timings);
  j["preprocess"] = preprocessJson(result.preprocess_stats);
  j["normals_invalid"] = result.normals.invalid;
  j["params"] = paramsJson(params);
  j["upd_nav_version"] = core::version();
  return j;
}

void writeJsonAtomically(const std::string& path, const nlohmann::json& j) {
  // replace: a file name with invalid UTF-8 must not make the whole summary unwritable.
  const std::string text = j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
  writeFileAtomically(path, [&](std::ostream& os) {
    os.write(text.data(), static_cast<std::streamsize>(text.size()));
  });
}

}  // namespace upd::io
