// Terrain::sampleSurface: the grid over the extent plus the vertical faces, with their truth.
#include "upd/sim/terrain.h"

#include "terrain_internal.h"

#include <algorithm>
#include <cmath>

namespace upd::sim {

using terrain_detail::kAcross_m;

// ----------------------------------------------------------------------------- sampling

SurfaceSamples Terrain::sampleSurface(double spacing_m) const {
  core::requireParam(std::isfinite(spacing_m) && spacing_m > 0, "Terrain::sampleSurface", "spacing_m",
               spacing_m, "must be > 0");
  const Eigen::Vector2d size = max_xy_ - min_xy_;
  const double nxd = std::floor(size.x() / spacing_m + 1e-9);
  const double nyd = std::floor(size.y() / spacing_m + 1e-9);
  core::requireParam((nxd + 1) * (nyd + 1) <= 2e8, "Terrain::sampleSurface", "spacing_m", spacing_m,
               "gives more than 2e8 grid points over the extent");
  const auto nx = static_cast<std::size_t>(nxd), ny = static_cast<std::size_t>(nyd);

  SurfaceSamples out;
  out.cloud.reserve((nx + 1) * (ny + 1));
  out.truth.reserve((nx + 1) * (ny + 1));
  for (std::size_t j = 0; j <= ny; ++j) {
    const double y = min_xy_.y() + j * spacing_m;
    for (std::size_t i = 0; i <= nx; ++i) {
      const double x = min_xy_.x() + i * spacing_m;
      out.cloud.push_back(static_cast<float>(x), static_cast<float>(y),
                          static_cast<float>(heightAt(x, y)));
      out.truth.push_back(truthAt(x, y));
    }
  }
  out.surface_points = out.cloud.size();

  // Vertical faces lie on shape edges. Where edges meet (a rectangle's corners) or coincide
  // (two shapes side by side) the face is sampled once, along the first edge.
  const auto onEarlierEdge = [&](std::size_t shape, std::size_t edge, const Eigen::Vector2d& q) {
    for (std::uint32_t other : cell_near_shapes_[cellOf(q.x(), q.y())]) {
      if (other > shape) continue;
      const std::size_t edges = other < shape ? edges_[other].size() : edge;
      for (std::size_t k = 0; k < edges; ++k) {
        const Segment& e = edges_[other][k];
        const Eigen::Vector2d d = e.b - e.a;
        const double s = std::clamp((q - e.a).dot(d) / d.squaredNorm(), 0.0, 1.0);
        if ((e.a + s * d - q).norm() < 1e-7) return true;
      }
    }
    return false;
  };
  for (std::size_t k = 0; k < shapes_.size(); ++k) {
    for (std::size_t e = 0; e < edges_[k].size(); ++e) {
      const Segment& seg = edges_[k][e];
      const Eigen::Vector2d d = seg.b - seg.a;
      const double len = d.norm();
      const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()) / len * kAcross_m;
      const auto samples = static_cast<std::size_t>(std::floor(len / spacing_m + 1e-9));
      for (std::size_t i = 0; i <= samples; ++i) {
        const Eigen::Vector2d q = seg.a + (i * spacing_m / len) * d;
        const Eigen::Vector2d q1 = q + n, q2 = q - n;
        if (!contains(q1.x(), q1.y()) || !contains(q2.x(), q2.y())) continue;
        const double h1 = heightAt(q1.x(), q1.y()), h2 = heightAt(q2.x(), q2.y());
        const double lo = std::min(h1, h2), hi = std::max(h1, h2);
        if (hi - lo <= spacing_m) continue;  // no face point strictly between
        if (onEarlierEdge(k, e, q)) continue;
        const core::Label label =
            hi - lo > truth_.max_step_m ? core::Label::NonTraversable : truthAt(q.x(), q.y());
        for (int m = 1; lo + m * spacing_m < hi - 1e-9; ++m) {
          out.cloud.push_back(static_cast<float>(q.x()), static_cast<float>(q.y()),
                              static_cast<float>(lo + m * spacing_m));
          out.truth.push_back(label);
        }
      }
    }
  }
  return out;
}

}  // namespace upd::sim
