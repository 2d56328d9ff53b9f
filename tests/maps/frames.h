// Building frames of scored world-frame points for the maps tests: the arrays a PipelineResult
// would give, owned here, viewed as PointsWorld.
#pragma once

#include "temp_dir.h"
#include "upd/maps/fusion.h"

#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace upd::test {

struct Frame {
  std::vector<float> x, y, z, zeta, slope, cost;
  std::vector<Label> label;

  void add(float px, float py, float pz, Label l, float zt = 1.f, float sl = 0.f, float c = 0.f) {
    x.push_back(px);
    y.push_back(py);
    z.push_back(pz);
    label.push_back(l);
    zeta.push_back(zt);
    slope.push_back(sl);
    cost.push_back(c);
  }
  /// n points spread inside the cell of side cell_m whose lower-left corner is (x0, y0).
  void fillCell(double x0, double y0, double cell_m, int n, Label l, float pz = 0.f,
                float zt = 1.f) {
    for (int k = 0; k < n; ++k) {
      const double u = (k % 7 + 0.5) / 7.0, v = (k / 7 % 7 + 0.5) / 7.0;
      add(static_cast<float>(x0 + u * cell_m), static_cast<float>(y0 + v * cell_m), pz, l, zt, 0.f,
          l == Label::NonTraversable ? 1.f : 0.f);
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

}  // namespace upd::test
