// Building frames of scored world-frame points for the maps tests: the arrays a PipelineResult
// would give, owned here, viewed as PointsWorld.
#pragma once

#include "temp_dir.h"
#include "upd/maps/fusion.h"
#include "upd/maps/grid_fusion.h"
#include "upd/maps/traversability_grid.h"

#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace upd::test {

struct Frame {
  std::vector<float> x, y, z, zeta, slope, cost;
  std::vector<core::Label> label;

  void add(float px, float py, float pz, core::Label l, float zt = 1.f, float sl = 0.f, float c = 0.f) {
    x.push_back(px);
    y.push_back(py);
    z.push_back(pz);
    label.push_back(l);
    zeta.push_back(zt);
    slope.push_back(sl);
    cost.push_back(c);
  }
  /// n points spread inside the cell of side cell_m whose lower-left corner is (x0, y0).
  void fillCell(double x0, double y0, double cell_m, int n, core::Label l, float pz = 0.f,
                float zt = 1.f) {
    for (int k = 0; k < n; ++k) {
      const double u = (k % 7 + 0.5) / 7.0, v = (k / 7 % 7 + 0.5) / 7.0;
      add(static_cast<float>(x0 + u * cell_m), static_cast<float>(y0 + v * cell_m), pz, l, zt, 0.f,
          l == core::Label::NonTraversable ? 1.f : 0.f);
    }
  }
  maps::PointsWorld view() const {
    maps::PointsWorld v;
    v.size = x.size();
    v.x = x.data();
    v.y = y.data();
    v.z = z.data();
    v.label = label.data();
    v.zeta = zeta.data();
    v.slope_rad = slope.data();
    v.cost = cost.data();
    return v;
  }
};

/// An 8 m square window of 0.1 m cells centred at (1, -2), so x in [-3, 5) and y in [-6, 2),
/// with an obstacle cell at (kObsX, kObsY), a traversable cell at (kFreeX, kFreeY), nothing
/// else: the fixture of the export and occupancy-grid tests.
constexpr double kObsX = 2.35, kObsY = -1.25, kFreeX = 0.55, kFreeY = -3.05;

inline maps::TraversabilityGrid twoCellGrid() {
  maps::GridParams gp;
  gp.cell_size_m = 0.1;
  gp.extent_m = 8.0;
  gp.follow_robot = false;
  gp.center_x_m = 1.0;
  gp.center_y_m = -2.0;
  maps::TraversabilityGrid g(gp);
  Frame f;
  f.fillCell(kObsX - 0.05, kObsY - 0.05, 0.1, 10, core::Label::NonTraversable);
  f.fillCell(kFreeX - 0.05, kFreeY - 0.05, 0.1, 10, core::Label::Traversable);
  for (int k = 0; k < 3; ++k) maps::integrateScan(g, f.view(), {1, -2}, k, maps::FusionParams{});
  return g;
}

}  // namespace upd::test
