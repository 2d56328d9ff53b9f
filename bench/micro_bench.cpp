// google/benchmark micro-benchmarks of the core stages on a generated Kinect frame (no shared
// data, no PCL): the organized normals, the fast UPD at growing d_m, and the exact UPD for
// contrast. Run: build/bench/upd_microbench [--benchmark_filter=...]. upd_bench is the report.
#include <benchmark/benchmark.h>

#include "upd/core/fast_normals.h"
#include "upd/core/fast_upd.h"
#include "upd/core/kdtree.h"
#include "upd/sim/render.h"
#include "upd/sim/terrain.h"

namespace core = upd::core;

namespace {

const upd::sim::RenderedScene& frame() {
  static const upd::sim::RenderedScene rs = [] {
    upd::sim::DepthNoise noise;
    noise.max_range_m = 5.0;
    return upd::sim::renderScene(upd::sim::makeWorld("mixed").terrain,
                            upd::sim::cameraPoseLookingAt({1.0, 0.3, 0.6}, {4.5, -0.4, 0.0}),
                            upd::core::CameraIntrinsics{}, noise, 7);
  }();
  return rs;
}

const upd::core::Normals& frameNormals() {
  static const upd::core::Normals n = [] {
    upd::core::NormalParams p;
    p.radius_m = 0.05;
    return upd::core::computeNormalsOrganized(frame().scene.cloud, p, frame().scene.up);
  }();
  return n;
}

void BM_OrganizedNormals(benchmark::State& state) {
  upd::core::NormalParams p;
  p.radius_m = 0.05;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        upd::core::computeNormalsOrganized(frame().scene.cloud, p, frame().scene.up));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(frame().scene.cloud.size()));
}
BENCHMARK(BM_OrganizedNormals)->Unit(benchmark::kMillisecond);

void BM_FastUpd(benchmark::State& state) {
  upd::core::UpdParams p;
  p.radius_m = static_cast<double>(state.range(0)) / 100.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(upd::core::computeUpdFast(frame().scene.cloud, frameNormals(), p));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(frame().scene.cloud.size()));
}
BENCHMARK(BM_FastUpd)->Arg(25)->Arg(50)->Arg(100)->Arg(200)->Unit(benchmark::kMillisecond);

// The exact UPD on a 1-in-16 subsample of the frame (the full frame takes minutes).
void BM_ExactUpdSubsampled(benchmark::State& state) {
  upd::core::PointCloud sub;
  upd::core::Normals n;
  const auto& c = frame().scene.cloud;
  for (std::size_t i = 0; i < c.size(); i += 16) {
    if (!c.isFinite(i) || !frameNormals().isValid(i)) continue;
    sub.push_back(c.x[i], c.y[i], c.z[i]);
    n.nx.push_back(frameNormals().nx[i]);
    n.ny.push_back(frameNormals().ny[i]);
    n.nz.push_back(frameNormals().nz[i]);
    n.curvature.push_back(frameNormals().curvature[i]);
  }
  const upd::core::KdTree tree(sub);
  upd::core::UpdParams p;
  p.radius_m = static_cast<double>(state.range(0)) / 100.0;
  for (auto _ : state) benchmark::DoNotOptimize(upd::core::computeUpd(sub, tree, n, p));
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(sub.size()));
}
BENCHMARK(BM_ExactUpdSubsampled)->Arg(25)->Arg(50)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
