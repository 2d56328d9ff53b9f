#include "upd/core/classify.h"

#include "fast_simd.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace upd::core {

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

namespace {

// acos(x) for x in [-1, 1] to 2e-7 rad (Abramowitz and Stegun 4.4.46 on |x|, reflected for
// x < 0): plain float arithmetic, so the loop below vectorizes; std::acos in double was a
// quarter of the stage.
inline float acosPoly(float x) {
  const float a = std::fabs(x);
  float p = -0.0012624911f;
  p = p * a + 0.0066700901f;
  p = p * a - 0.0170881256f;
  p = p * a + 0.0308918810f;
  p = p * a - 0.0501743046f;
  p = p * a + 0.0889789874f;
  p = p * a - 0.2145988016f;
  p = p * a + 1.5707963050f;
  const float t = 1.f - a;
  const float root = t * detail::rsqrtNewton(std::max(t, 1e-30f));
  const float r = root * p;
  return x < 0.f ? static_cast<float>(M_PI) - r : r;
}

struct ClassifyConstants {
  float zeta_min, zeta_caution, inv_span, max_slope, inv_max_slope, ux, uy, uz;
  std::uint32_t min_k;
};

struct LabelCounts {
  std::size_t traversable = 0, non_traversable = 0;
};

// Points [begin, end): branch-free (every value computed, then selected), so that the loop
// vectorizes in each UPD_VECTOR_CLONES version. Returns the counts of the two labels written.
UPD_VECTOR_CLONES
LabelCounts classifyRange(const float* __restrict rx, const float* __restrict ry,
                   const float* __restrict rz, const float* __restrict zeta,
                   const std::uint32_t* __restrict k, const ClassifyConstants& c, std::size_t begin,
                   std::size_t end, std::uint8_t* __restrict label_out, float* __restrict cost,
                   float* __restrict slope_out) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::uint32_t trav = 0, nontrav = 0;  // (32-bit lanes, as the floats': one vector width)
  for (std::size_t i = begin; i < end; ++i) {
    const float z = zeta[i];
    const int valid = (z == z ? 1 : 0) & (k[i] >= c.min_k ? 1 : 0);
    const float x = rx[i], y = ry[i], w = rz[i];
    const float d2 = x * x + y * y + w * w;
    const float inv = detail::rsqrtNewton(std::max(d2, 1e-30f));
    const float cosine = std::min(1.f, std::max(-1.f, (x * c.ux + y * c.uy + w * c.uz) * inv));
    // A vanishing r (normals cancelling) has no direction: treat it as the steepest slope.
    const float slope = d2 > 0.f ? acosPoly(cosine) : static_cast<float>(M_PI);
    const int blocked = (z < c.zeta_min ? 1 : 0) | (slope > c.max_slope ? 1 : 0);
    const float zeta_cost = std::min(1.f, std::max(0.f, (c.zeta_caution - z) * c.inv_span));
    const float ratio = slope * c.inv_max_slope;
    const float trav_cost = std::max(zeta_cost, ratio * ratio);
    // Label values: Traversable 0, NonTraversable 1, Unknown 2.
    label_out[i] = static_cast<std::uint8_t>(2 - valid * (2 - blocked));
    cost[i] = valid ? (blocked ? 1.f : trav_cost) : nan;
    slope_out[i] = valid ? slope : nan;
    trav += static_cast<std::uint32_t>(valid & (1 - blocked));
    nontrav += static_cast<std::uint32_t>(valid & blocked);
  }
  return {trav, nontrav};
}

}  // namespace

void classify(const UpdResult& upd, const Eigen::Vector3f& up, const ClassifyParams& params,
              Classification& out) {
  params.validate();
  const std::size_t n = upd.size();
  out.label.resize(n);
  out.cost.resize(n);
  out.slope_rad.resize(n);
  ClassifyConstants c{};
  c.zeta_min = static_cast<float>(params.zeta_min);
  c.zeta_caution = static_cast<float>(params.zeta_caution);
  const float span = c.zeta_caution - c.zeta_min;
  c.inv_span = span > 0.f ? 1.f / span : 0.f;
  c.max_slope = static_cast<float>(params.max_slope_rad);
  c.inv_max_slope = 1.f / c.max_slope;
  c.ux = up.x(), c.uy = up.y(), c.uz = up.z();
  c.min_k = static_cast<std::uint32_t>(params.min_neighbors);
  static_assert(sizeof(Label) == 1, "classifyRange writes labels as bytes");
  constexpr std::size_t kChunk = 8192;
  const auto n_chunks = static_cast<std::ptrdiff_t>((n + kChunk - 1) / kChunk);
  std::size_t trav = 0, nontrav = 0;
#pragma omp parallel for schedule(static) reduction(+ : trav, nontrav)
  for (std::ptrdiff_t ch = 0; ch < n_chunks; ++ch) {
    const std::size_t begin = static_cast<std::size_t>(ch) * kChunk;
    const std::size_t end = std::min(n, begin + kChunk);
    const LabelCounts counts = classifyRange(
        upd.rx.data(), upd.ry.data(), upd.rz.data(), upd.zeta.data(), upd.k.data(), c, begin,
        end, reinterpret_cast<std::uint8_t*>(out.label.data()), out.cost.data(),
        out.slope_rad.data());
    trav += counts.traversable;
    nontrav += counts.non_traversable;
  }
  out.traversable = trav;
  out.non_traversable = nontrav;
  out.unknown = n - trav - nontrav;
}

Classification classify(const UpdResult& upd, const Eigen::Vector3f& up,
                        const ClassifyParams& params) {
  Classification out;
  classify(upd, up, params, out);
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

}  // namespace upd::core
