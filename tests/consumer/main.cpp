// Scores a generated flat plane with the installed upd::core and prints its zeta (1 on a
// plane), and fuses it into a upd::maps grid: what a project using the package does first.
#include <upd/core/pipeline.h>
#include <upd/maps/traversability_grid.h>

#include <cmath>
#include <cstdio>

namespace core = upd::core;

int main() {
  upd::core::PointCloud plane;  // 2 m x 2 m at 2 cm, z = 0
  for (int i = 0; i <= 100; ++i) {
    for (int j = 0; j <= 100; ++j) plane.push_back(0.02f * i - 1.f, 0.02f * j - 1.f, 0.f);
  }
  const upd::core::PipelineResult res = upd::core::runPipeline(plane, upd::core::PipelineParams{});
  double zeta_sum = 0;
  std::size_t scored = 0;
  for (std::size_t i = 0; i < res.upd.size(); ++i) {
    if (!res.upd.isValid(i)) continue;
    zeta_sum += res.upd.zeta[i];
    ++scored;
  }
  if (scored == 0) {
    std::fprintf(stderr, "no point was scored\n");
    return 1;
  }
  const double zeta = zeta_sum / static_cast<double>(scored);
  const upd::maps::TraversabilityGrid grid;
  std::printf("zeta %.4f over %zu points; traversable %zu; grid %d x %d cells of %.2f m\n", zeta,
              scored, res.classes.traversable, grid.sizeX(), grid.sizeY(), grid.cellSize());
  return std::fabs(zeta - 1.0) < 1e-3 ? 0 : 1;
}
