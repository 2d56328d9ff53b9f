// The core pipeline (pre-processing, normals, UPD, classification) on an arbitrary cloud: the
// input's bytes are the floats x, y, z of up to 4096 points (NaN, Inf, denormals and 1e38
// included; up to 512 on the exact path, whose cost grows as the square of the points within
// the radius: 4096 points in one ball take minutes instrumented, a limit, not a fault), scored
// with the default parameters on the fast and the exact path. The pipeline must return
// (counting what it cannot score) or refuse with std::invalid_argument.
#include "upd/core/pipeline.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <stdexcept>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const bool exact = data[0] & 1;
  const bool preprocess = data[0] & 2;
  ++data;
  --size;
  const std::size_t n = std::min<std::size_t>(size / 12, exact ? 512 : 4096);
  upd::core::PointCloud cloud;
  cloud.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    float v[3];
    std::memcpy(v, data + 12 * i, 12);
    cloud.push_back(v[0], v[1], v[2]);
  }
  upd::core::PipelineParams params;
  if (exact) params.upd.method = upd::core::UpdMethod::Exact;
  if (!preprocess) params.preprocess.disableAll();
  try {
    const upd::core::PipelineResult r = upd::core::runPipeline(cloud, params);
    if (r.upd.zeta.size() != r.cloud.size()) __builtin_trap();
  } catch (const std::invalid_argument&) {
    // a cloud the parameters cannot handle (an extent beyond the grids), said so
  }
  return 0;
}
