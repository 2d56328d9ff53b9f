// Terrain::raycast in named steps: clip the ray to the extent and to the height bound, walk the
// index cells it crosses (Amanatides-Woo), march the cells it may hit, refine the hit.
#include "upd/sim/terrain.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace upd::sim {

namespace {

// Horizontal step of the ray march inside a cell that may be hit [m]: thinner features than
// this could be stepped over; every primitive of the worlds is at least 10x wider.
constexpr double kMarchStep_m = 0.01;
// Ray parameter tolerance of the bisection [m] and height tolerance of a hit [m].
constexpr double kBisectTol_m = 1e-7;
constexpr double kSurfaceTol_m = 1e-9;

// The part [t_in, t_out] of the ray over the extent (slab test); false when it misses it.
bool clipToExtent(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector2d& lo,
                  const Eigen::Vector2d& hi, double& t_in, double& t_out) {
  for (int a = 0; a < 2; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (o[a] < lo[a] || o[a] > hi[a]) t_in = std::numeric_limits<double>::infinity();
      continue;
    }
    double t1 = (lo[a] - o[a]) / d[a], t2 = (hi[a] - o[a]) / d[a];
    if (t1 > t2) std::swap(t1, t2);
    t_in = std::max(t_in, t1);
    t_out = std::min(t_out, t2);
  }
  return t_in <= t_out;
}

}  // namespace

/// The ray origin + t d (d unit) over a terrain: height above the surface along it, the plane
/// z = 0 outside the extent, and the refinement of a bracketed hit.
struct Terrain::Ray {
  const Terrain& terrain;
  const Eigen::Vector3d& o;
  Eigen::Vector3d d;

  Eigen::Vector3d point(double t) const { return o + t * d; }
  double above(double t) const {
    const Eigen::Vector3d p = point(t);
    return p.z() - terrain.heightAt(p.x(), p.y());
  }
  // Outside the extent the world is the plane z = 0.
  std::optional<Eigen::Vector3d> planeHit(double ta, double tb) const {
    if (d.z() >= 0.0) return std::nullopt;
    const double t = -o.z() / d.z();
    if (t >= ta && t <= tb) return point(t);
    return std::nullopt;
  }
  // Between a parameter above the surface and one on or below it. Regula falsi with the
  // Illinois rule (the value kept at an end that stays twice is halved, so the bracket shrinks
  // from both sides) converges superlinearly on smooth relief; at a vertical face a step barely
  // moves, so after two steps in a row that do not halve the bracket one bisection follows (the
  // hit within kBisectTol_m).
  Eigen::Vector3d refine(double lo, double hi) const {
    double f_lo = above(lo), f_hi = above(hi);
    int side = 0, slow = 0;
    for (int i = 0; i < 128 && hi - lo > kBisectTol_m; ++i) {
      const double width = hi - lo;
      const bool bisect = slow >= 2 || !(f_lo - f_hi > 0.0);
      const double t = bisect ? 0.5 * (lo + hi) : lo + width * f_lo / (f_lo - f_hi);
      const double f = above(t);
      if (std::abs(f) <= kSurfaceTol_m) return point(t);
      if (f > 0.0) {
        lo = t;
        f_lo = f;
        if (side == 1) f_hi *= 0.5;
        side = 1;
      } else {
        hi = t;
        f_hi = f;
        if (side == -1) f_lo *= 0.5;
        side = -1;
      }
      slow = hi - lo > 0.5 * width ? slow + 1 : 0;
    }
    return point(f_lo - f_hi > 0.0 ? lo + (hi - lo) * f_lo / (f_lo - f_hi) : hi);
  }
};

std::optional<Eigen::Vector3d> Terrain::raycast(const Eigen::Vector3d& origin,
                                                const Eigen::Vector3d& dir,
                                                double max_range_m) const {
  const double dir_norm = dir.norm();
  if (!std::isfinite(dir_norm) || dir_norm <= 0.0) {
    throw std::invalid_argument("Terrain::raycast: dir must be finite and non-zero");
  }
  if (!origin.allFinite()) {
    throw std::invalid_argument("Terrain::raycast: origin must be finite");
  }
  if (!(max_range_m > 0.0)) return std::nullopt;
  const Ray ray{*this, origin, dir / dir_norm};
  const Eigen::Vector3d& o = origin;
  const Eigen::Vector3d& d = ray.d;
  if (ray.above(0.0) < 0.0) return std::nullopt;                   // starts under the surface
  if (d.z() >= 0.0 && o.z() > max_height_m_) return std::nullopt;  // the sky

  double t_in = 0.0, t_out = max_range_m;
  if (!clipToExtent(o, d, min_xy_, max_xy_, t_in, t_out)) return ray.planeHit(0.0, max_range_m);
  if (t_in > 0.0) {
    if (auto hit = ray.planeHit(0.0, t_in)) return hit;
  }
  // Nothing can be hit while the ray is above the highest point.
  if (d.z() < 0.0 && o.z() > max_height_m_) {
    t_in = std::max(t_in, (max_height_m_ - o.z()) / d.z());
    if (t_in > t_out) return t_out < max_range_m ? ray.planeHit(t_out, max_range_m) : std::nullopt;
  }
  if (ray.above(t_in) <= 0.0) return ray.point(t_in);  // enters through a face on the border

  bool to_sky = false;
  if (auto hit = walkCells(ray, t_in, t_out, to_sky)) return hit;
  if (!to_sky && t_out < max_range_m) return ray.planeHit(t_out, max_range_m);
  return std::nullopt;
}

// Walk the cells the ray crosses (Amanatides-Woo); skip a cell where the ray stays above its
// height bound, otherwise march it in small horizontal steps from where it descends to the
// bound. to_sky: the ray climbed above everything (no hit farther either).
std::optional<Eigen::Vector3d> Terrain::walkCells(const Ray& ray, double t_in, double t_out,
                                                  bool& to_sky) const {
  const Eigen::Vector3d& o = ray.o;
  const Eigen::Vector3d& d = ray.d;
  const Eigen::Vector3d p_in = ray.point(t_in);
  int ix = std::clamp(static_cast<int>(std::floor((p_in.x() - min_xy_.x()) / cell_m_)), 0, nx_ - 1);
  int iy = std::clamp(static_cast<int>(std::floor((p_in.y() - min_xy_.y()) / cell_m_)), 0, ny_ - 1);
  const double inf = std::numeric_limits<double>::infinity();
  const int step_x = d.x() > 0 ? 1 : (d.x() < 0 ? -1 : 0);
  const int step_y = d.y() > 0 ? 1 : (d.y() < 0 ? -1 : 0);
  double t_next_x =
      step_x == 0 ? inf : (min_xy_.x() + (ix + (step_x > 0 ? 1 : 0)) * cell_m_ - o.x()) / d.x();
  double t_next_y =
      step_y == 0 ? inf : (min_xy_.y() + (iy + (step_y > 0 ? 1 : 0)) * cell_m_ - o.y()) / d.y();
  const double dt_x = step_x == 0 ? inf : cell_m_ / std::abs(d.x());
  const double dt_y = step_y == 0 ? inf : cell_m_ / std::abs(d.y());
  const double horizontal = std::hypot(d.x(), d.y());
  const double march_dt = horizontal > 1e-12 ? kMarchStep_m / horizontal : inf;

  double t = t_in, t_above = t_in;
  while (true) {
    const double t_end = std::min({t_next_x, t_next_y, t_out});
    const std::size_t cell = static_cast<std::size_t>(iy) * nx_ + ix;
    if (auto hit = marchCell(ray, t, t_end, cell_max_m_[cell], march_dt, cell_slope_[cell],
                             t_above)) {
      return hit;
    }
    if (t_end >= t_out) break;
    if (d.z() >= 0.0 && o.z() + t_end * d.z() > max_height_m_) {  // climbing above everything
      to_sky = true;
      return std::nullopt;
    }
    t = t_end;
    if (t_next_x < t_next_y) {
      ix += step_x;
      t_next_x += dt_x;
    } else {
      iy += step_y;
      t_next_y += dt_y;
    }
    if (ix < 0 || ix >= nx_ || iy < 0 || iy >= ny_) break;  // rounding at the far border
  }
  return std::nullopt;
}

// One cell [t, t_end] of the walk under the height bound: skipped when the ray stays above it,
// else marched until the ray is on or under the surface (then refined from the last parameter
// above it, t_above, which the march advances). A step is march_dt, or longer where the
// surface's slope is bounded (slope_bound: |grad h| <= it in this cell; infinity: vertical
// faces): a ray `above` over the surface that descends at -d.z per unit of t against a surface
// rising at most slope_bound x horizontal cannot meet it within above / (slope_bound x
// horizontal - d.z), so the longer step skips no crossing the march_dt steps would find.
std::optional<Eigen::Vector3d> Terrain::marchCell(const Ray& ray, double t, double t_end,
                                                  double bound, double march_dt,
                                                  double slope_bound, double& t_above) const {
  const double za = ray.o.z() + t * ray.d.z(), zb = ray.o.z() + t_end * ray.d.z();
  if (std::min(za, zb) > bound) {
    t_above = std::max(t_above, t_end);
    return std::nullopt;
  }
  double tc = t;
  if (za > bound && ray.d.z() < 0.0) tc = std::max(t, (bound - ray.o.z()) / ray.d.z());
  const double closing =
      std::isfinite(slope_bound) ? slope_bound * std::hypot(ray.d.x(), ray.d.y()) - ray.d.z() : 0.0;
  while (true) {
    const double above = ray.above(tc);
    if (above <= 0.0) return ray.refine(t_above, tc);
    t_above = tc;
    if (tc >= t_end) return std::nullopt;
    double dt = march_dt;
    if (std::isfinite(slope_bound)) {
      dt = closing > 0.0 ? std::max(dt, above / closing) : std::numeric_limits<double>::infinity();
    }
    tc = std::min(tc + dt, t_end);
  }
}

}  // namespace upd::sim
