#include "upd/sim/terrain.h"

#include "terrain_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace upd::sim {

using terrain_detail::kAcross_m;
using terrain_detail::kPi;

namespace {

// Spacing of the samples along an edge when looking for a discontinuity near a point [m].
constexpr double kEdgeProbe_m = 0.005;
// Finite-difference step of the slope [m]: small so a step below max_step_m does not read as
// a steep slope except within this distance of it.
constexpr double kSlopeStep_m = 1e-4;

bool finite(const Eigen::Vector2d& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); }

}  // namespace

// ----------------------------------------------------------------------------- validation

void TruthParams::validate() const {
  core::requireParam(std::isfinite(max_slope_rad) && max_slope_rad > 0 && max_slope_rad < kPi / 2,
               "TruthParams", "max_slope_rad", max_slope_rad, "must be in (0, pi/2)");
  core::requireParam(std::isfinite(max_step_m) && max_step_m > 0, "TruthParams", "max_step_m", max_step_m,
               "must be > 0");
  core::requireParam(std::isfinite(border_m) && border_m >= 0, "TruthParams", "border_m", border_m,
               "must be >= 0");
}

double Ramp::slopeLength() const { return height_m / std::tan(slope_rad); }

void Ramp::validate() const {
  core::requireParam(finite(start_xy), "Ramp", "start_xy", start_xy.transpose(), "must be finite");
  core::requireParam(std::isfinite(yaw_rad), "Ramp", "yaw_rad", yaw_rad, "must be finite");
  core::requireParam(std::isfinite(slope_rad) && slope_rad > 0 && slope_rad <= 60.0 * core::kDegToRad, "Ramp",
               "slope_rad", slope_rad, "must be in (0, 60 deg]");
  core::requireParam(std::isfinite(width_m) && width_m > 0, "Ramp", "width_m", width_m, "must be > 0");
  core::requireParam(std::isfinite(height_m) && height_m > 0, "Ramp", "height_m", height_m,
               "must be > 0");
  core::requireParam(std::isfinite(platform_length_m) && platform_length_m >= 0, "Ramp",
               "platform_length_m", platform_length_m, "must be >= 0");
}

void Box::validate() const {
  core::requireParam(finite(center_xy), "Box", "center_xy", center_xy.transpose(), "must be finite");
  core::requireParam(std::isfinite(length_m) && length_m > 0, "Box", "length_m", length_m, "must be > 0");
  core::requireParam(std::isfinite(width_m) && width_m > 0, "Box", "width_m", width_m, "must be > 0");
  core::requireParam(std::isfinite(height_m) && height_m > 0, "Box", "height_m", height_m, "must be > 0");
  core::requireParam(std::isfinite(yaw_rad), "Box", "yaw_rad", yaw_rad, "must be finite");
}

void Ditch::validate() const {
  core::requireParam(finite(center_xy), "Ditch", "center_xy", center_xy.transpose(), "must be finite");
  core::requireParam(std::isfinite(length_m) && length_m > 0, "Ditch", "length_m", length_m,
               "must be > 0");
  core::requireParam(std::isfinite(width_m) && width_m > 0, "Ditch", "width_m", width_m, "must be > 0");
  core::requireParam(std::isfinite(depth_m) && depth_m > 0, "Ditch", "depth_m", depth_m, "must be > 0");
  core::requireParam(std::isfinite(yaw_rad), "Ditch", "yaw_rad", yaw_rad, "must be finite");
}

void Rock::validate() const {
  core::requireParam(finite(center_xy), "Rock", "center_xy", center_xy.transpose(), "must be finite");
  core::requireParam(std::isfinite(radius_x_m) && radius_x_m > 0, "Rock", "radius_x_m", radius_x_m,
               "must be > 0");
  core::requireParam(std::isfinite(radius_y_m) && radius_y_m > 0, "Rock", "radius_y_m", radius_y_m,
               "must be > 0");
  core::requireParam(std::isfinite(height_m) && height_m > 0, "Rock", "height_m", height_m,
               "must be > 0");
  core::requireParam(std::isfinite(yaw_rad), "Rock", "yaw_rad", yaw_rad, "must be finite");
}

void Stairs::validate() const {
  core::requireParam(finite(start_xy), "Stairs", "start_xy", start_xy.transpose(), "must be finite");
  core::requireParam(std::isfinite(yaw_rad), "Stairs", "yaw_rad", yaw_rad, "must be finite");
  core::requireParam(std::isfinite(width_m) && width_m > 0, "Stairs", "width_m", width_m, "must be > 0");
  core::requireParam(steps >= 1, "Stairs", "steps", steps, "must be >= 1");
  core::requireParam(std::isfinite(rise_m) && rise_m > 0, "Stairs", "rise_m", rise_m, "must be > 0");
  core::requireParam(std::isfinite(run_m) && run_m > 0, "Stairs", "run_m", run_m, "must be > 0");
  core::requireParam(std::isfinite(top_length_m) && top_length_m >= 0, "Stairs", "top_length_m",
               top_length_m, "must be >= 0");
}

void Roughness::validate() const {
  core::requireParam(std::isfinite(rms_height_m) && rms_height_m >= 0, "Roughness", "rms_height_m",
               rms_height_m, "must be >= 0");
  core::requireParam(std::isfinite(wavelength_m) && wavelength_m > 0, "Roughness", "wavelength_m",
               wavelength_m, "must be > 0");
  core::requireParam(seed >= 0, "Roughness", "seed", seed, "must be >= 0");
}

// ----------------------------------------------------------------------------- construction

Terrain::Terrain(const Eigen::Vector2d& min_xy, const Eigen::Vector2d& max_xy,
                 const TruthParams& truth)
    : min_xy_(min_xy), max_xy_(max_xy), truth_(truth) {
  core::requireParam(finite(min_xy), "Terrain", "min_xy", min_xy.transpose(), "must be finite");
  core::requireParam(finite(max_xy) && max_xy.x() > min_xy.x() && max_xy.y() > min_xy.y(), "Terrain",
               "max_xy", max_xy.transpose(), "must be finite and > min_xy on both axes");
  truth_.validate();
  rebuildIndex();
}

Terrain::Shape Terrain::orientedShape(const Eigen::Vector2d& origin, double yaw_rad) {
  Shape s;
  s.origin = origin;
  s.cos_yaw = std::cos(yaw_rad);
  s.sin_yaw = std::sin(yaw_rad);
  return s;
}

Terrain& Terrain::add(const Ramp& p) {
  p.validate();
  Shape s = orientedShape(p.start_xy, p.yaw_rad);
  s.kind = Shape::Kind::Ramp;
  s.u_min = 0.0;
  s.u_max = p.slopeLength() + p.platform_length_m;
  s.v_half = 0.5 * p.width_m;
  s.height_m = s.max_height_m = p.height_m;
  s.tan_slope = std::tan(p.slope_rad);
  ramps_.push_back(p);
  addShape(s);
  return *this;
}

Terrain& Terrain::add(const Box& p) {
  p.validate();
  Shape s = orientedShape(p.center_xy, p.yaw_rad);
  s.kind = Shape::Kind::Box;
  s.u_min = -0.5 * p.length_m;
  s.u_max = 0.5 * p.length_m;
  s.v_half = 0.5 * p.width_m;
  s.height_m = s.max_height_m = p.height_m;
  s.wall = p.wall;
  boxes_.push_back(p);
  addShape(s);
  return *this;
}

Terrain& Terrain::add(const Ditch& p) {
  p.validate();
  Shape s = orientedShape(p.center_xy, p.yaw_rad);
  s.kind = Shape::Kind::Ditch;
  s.u_min = -0.5 * p.length_m;
  s.u_max = 0.5 * p.length_m;
  s.v_half = 0.5 * p.width_m;
  s.height_m = -p.depth_m;
  s.max_height_m = 0.0;  // lowers the surface: never raises a cell's bound
  ditches_.push_back(p);
  addShape(s);
  return *this;
}

Terrain& Terrain::add(const Rock& p) {
  p.validate();
  Shape s = orientedShape(p.center_xy, p.yaw_rad);
  s.kind = Shape::Kind::Rock;
  s.u_min = -p.radius_x_m;
  s.u_max = p.radius_x_m;
  s.v_half = p.radius_y_m;
  s.radius_u_m = p.radius_x_m;
  s.radius_v_m = p.radius_y_m;
  s.height_m = s.max_height_m = p.height_m;
  rocks_.push_back(p);
  addShape(s);
  return *this;
}

Terrain& Terrain::add(const Stairs& p) {
  p.validate();
  Shape s = orientedShape(p.start_xy, p.yaw_rad);
  s.kind = Shape::Kind::Stairs;
  s.u_min = 0.0;
  s.u_max = p.steps * p.run_m + p.top_length_m;
  s.v_half = 0.5 * p.width_m;
  s.height_m = p.rise_m;
  s.max_height_m = p.steps * p.rise_m;
  s.run_m = p.run_m;
  s.steps = p.steps;
  stairs_.push_back(p);
  addShape(s);
  return *this;
}

Terrain& Terrain::setRoughness(const Roughness& r) {
  r.validate();
  roughness_ = r;
  waves_.clear();
  roughness_bound_m_ = 0.0;
  roughness_gradient_bound_ = 0.0;
  if (r.rms_height_m > 0) {
    constexpr int kWaves = 8;
    // Each wave a sin(.) has variance a^2 / 2; 8 of them sum to rms^2 with a = rms / 2.
    const double amplitude = r.rms_height_m * std::sqrt(2.0 / kWaves);
    std::mt19937 rng(static_cast<std::uint32_t>(r.seed));
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < kWaves; ++i) {
      const double theta = 2.0 * kPi * unit(rng);
      const double wavelength = r.wavelength_m * (0.5 + unit(rng));
      const double phase = 2.0 * kPi * unit(rng);
      const double k = 2.0 * kPi / wavelength;
      waves_.emplace_back(k * std::cos(theta), k * std::sin(theta), phase, amplitude);
      roughness_gradient_bound_ += amplitude * k;
    }
    roughness_bound_m_ = kWaves * amplitude;
  }
  rebuildIndex();
  return *this;
}

Terrain& Terrain::setTruthParams(const TruthParams& t) {
  t.validate();
  truth_ = t;
  rebuildIndex();
  return *this;
}

void Terrain::addShape(const Shape& s) {
  shapes_.push_back(s);
  edges_.push_back(shapeEdges(s));
  indexShape(shapes_.size() - 1);
}

void Terrain::rebuildIndex() {
  const Eigen::Vector2d size = max_xy_ - min_xy_;
  // 0.1 m cells, coarser for huge extents so the index stays below ~250k cells.
  cell_m_ = std::max(0.1, std::sqrt(size.x() * size.y() / 250000.0));
  inv_cell_ = 1.0 / cell_m_;
  nx_ = std::max(1, static_cast<int>(std::ceil(size.x() / cell_m_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(size.y() / cell_m_)));
  const std::size_t n = static_cast<std::size_t>(nx_) * ny_;
  cell_shapes_.assign(n, {});
  cell_near_shapes_.assign(n, {});
  cell_max_m_.assign(n, roughness_bound_m_);
  cell_slope_.assign(n, roughness_gradient_bound_);
  for (std::size_t i = 0; i < shapes_.size(); ++i) indexShape(i);
  max_height_m_ = *std::max_element(cell_max_m_.begin(), cell_max_m_.end());
}

void Terrain::indexShape(std::size_t shape_index) {
  const Shape& s = shapes_[shape_index];
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector2d hi = -lo;
  for (double u : {s.u_min, s.u_max}) {
    for (double v : {-s.v_half, s.v_half}) {
      const Eigen::Vector2d p(s.origin.x() + s.cos_yaw * u - s.sin_yaw * v,
                              s.origin.y() + s.sin_yaw * u + s.cos_yaw * v);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  const auto cover = [&](double pad, auto&& fn) {
    const int ix0 =
        std::max(0, static_cast<int>(std::floor((lo.x() - pad - min_xy_.x()) / cell_m_)));
    const int iy0 =
        std::max(0, static_cast<int>(std::floor((lo.y() - pad - min_xy_.y()) / cell_m_)));
    const int ix1 =
        std::min(nx_ - 1, static_cast<int>(std::floor((hi.x() + pad - min_xy_.x()) / cell_m_)));
    const int iy1 =
        std::min(ny_ - 1, static_cast<int>(std::floor((hi.y() + pad - min_xy_.y()) / cell_m_)));
    for (int iy = iy0; iy <= iy1; ++iy) {
      for (int ix = ix0; ix <= ix1; ++ix) fn(static_cast<std::size_t>(iy) * nx_ + ix);
    }
  };
  const auto id = static_cast<std::uint32_t>(shape_index);
  // The padding makes each cell's lists and bound valid on its closed boundary.
  constexpr double kPad_m = 1e-6;
  const double inf = std::numeric_limits<double>::infinity();
  // The surface is max(roughness, shapes): its slope is bounded by the steepest of them where
  // no footprint ends (an edge: a jump) and no rock stands (vertical at its foot).
  const double shape_slope = s.kind == Shape::Kind::Rock   ? inf
                             : s.kind == Shape::Kind::Ramp ? s.tan_slope
                                                           : 0.0;
  cover(kPad_m, [&](std::size_t c) {
    cell_shapes_[c].push_back(id);
    cell_max_m_[c] = std::max(cell_max_m_[c], s.max_height_m + roughness_bound_m_);
    max_height_m_ = std::max(max_height_m_, cell_max_m_[c]);
    cell_slope_[c] = std::max(cell_slope_[c], roughness_gradient_bound_ + shape_slope);
  });
  cover(truth_.border_m + kPad_m, [&](std::size_t c) { cell_near_shapes_[c].push_back(id); });
  // Every cell an edge passes through (or within kPad_m of) has no slope bound: the edge is
  // walked in steps of at most half a cell, and the cells of each step's bounding box marked.
  for (const Segment& seg : edges_[shape_index]) {
    const int n = 1 + static_cast<int>(std::ceil(2.0 * (seg.b - seg.a).norm() / cell_m_));
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d p = seg.a + (seg.b - seg.a) * (static_cast<double>(k) / n);
      const Eigen::Vector2d q = seg.a + (seg.b - seg.a) * (static_cast<double>(k + 1) / n);
      const auto index = [&](double v, double origin, int cells) {
        return std::clamp(static_cast<int>(std::floor((v - origin) / cell_m_)), 0, cells - 1);
      };
      const int ix0 = index(std::min(p.x(), q.x()) - kPad_m, min_xy_.x(), nx_);
      const int ix1 = index(std::max(p.x(), q.x()) + kPad_m, min_xy_.x(), nx_);
      const int iy0 = index(std::min(p.y(), q.y()) - kPad_m, min_xy_.y(), ny_);
      const int iy1 = index(std::max(p.y(), q.y()) + kPad_m, min_xy_.y(), ny_);
      for (int iy = iy0; iy <= iy1; ++iy) {
        for (int ix = ix0; ix <= ix1; ++ix) cell_slope_[static_cast<std::size_t>(iy) * nx_ + ix] = inf;
      }
    }
  }
}

std::vector<Terrain::Segment> Terrain::shapeEdges(const Shape& s) const {
  std::vector<Segment> out;
  if (s.kind == Shape::Kind::Rock) return out;  // a continuous surface: no edge
  const auto world = [&](double u, double v) {
    return Eigen::Vector2d(s.origin.x() + s.cos_yaw * u - s.sin_yaw * v,
                           s.origin.y() + s.sin_yaw * u + s.cos_yaw * v);
  };
  const Eigen::Vector2d c00 = world(s.u_min, -s.v_half), c10 = world(s.u_max, -s.v_half),
                        c11 = world(s.u_max, s.v_half), c01 = world(s.u_min, s.v_half);
  out.push_back({c00, c10});
  out.push_back({c10, c11});
  out.push_back({c11, c01});
  out.push_back({c01, c00});
  if (s.kind == Shape::Kind::Stairs) {
    for (int k = 1; k < s.steps; ++k) {
      out.push_back({world(k * s.run_m, -s.v_half), world(k * s.run_m, s.v_half)});
    }
  }
  return out;
}

// ----------------------------------------------------------------------------- queries

bool Terrain::contains(double x, double y) const {
  return x >= min_xy_.x() && x <= max_xy_.x() && y >= min_xy_.y() && y <= max_xy_.y();
}

std::size_t Terrain::cellOf(double x, double y) const {
  // Truncation, not std::floor (a libm call without SSE4.1): negative offsets clamp to 0 anyway.
  const int ix = std::clamp(static_cast<int>((x - min_xy_.x()) * inv_cell_), 0, nx_ - 1);
  const int iy = std::clamp(static_cast<int>((y - min_xy_.y()) * inv_cell_), 0, ny_ - 1);
  return static_cast<std::size_t>(iy) * nx_ + ix;
}

double Terrain::roughnessAt(double x, double y) const {
  double h = 0.0;
  for (const Eigen::Vector4d& w : waves_) {
    h += w[3] * terrain_detail::fastSin(w[0] * x + w[1] * y + w[2]);
  }
  return h;
}

double Terrain::shapeHeight(const Shape& s, double x, double y, bool& inside) const {
  const double dx = x - s.origin.x(), dy = y - s.origin.y();
  const double u = s.cos_yaw * dx + s.sin_yaw * dy;
  const double v = -s.sin_yaw * dx + s.cos_yaw * dy;
  if (s.kind == Shape::Kind::Rock) {
    const double q =
        (u / s.radius_u_m) * (u / s.radius_u_m) + (v / s.radius_v_m) * (v / s.radius_v_m);
    inside = q <= 1.0;
    return inside ? s.height_m * std::sqrt(1.0 - q) : 0.0;
  }
  inside = u >= s.u_min && u <= s.u_max && std::abs(v) <= s.v_half;
  if (!inside) return 0.0;
  switch (s.kind) {
    case Shape::Kind::Ramp:
      return std::min(u * s.tan_slope, s.height_m);
    case Shape::Kind::Stairs: {
      const int k = std::min(static_cast<int>(std::floor(u / s.run_m)), s.steps - 1);
      return (k + 1) * s.height_m;
    }
    default:
      return s.height_m;
  }
}

double Terrain::heightAt(double x, double y) const {
  if (!contains(x, y)) return 0.0;
  double shapes = -std::numeric_limits<double>::infinity();
  double ditch_floor = std::numeric_limits<double>::infinity();
  for (std::uint32_t id : cell_shapes_[cellOf(x, y)]) {
    const Shape& s = shapes_[id];
    bool inside = false;
    const double sh = shapeHeight(s, x, y, inside);
    if (!inside) continue;
    if (s.kind == Shape::Kind::Ditch) {
      ditch_floor = std::min(ditch_floor, sh);
    } else {
      shapes = std::max(shapes, sh);
    }
  }
  if (std::isfinite(ditch_floor)) return ditch_floor;
  // The surface is max(roughness, shapes), and the roughness never exceeds its bound (the
  // amplitudes' sum; 1e-9 m covers the rounding of the sines and of the sum): under a shape
  // standing higher its waves, most of the cost of a height, need not be summed.
  if (shapes > roughness_bound_m_ + 1e-9) return shapes;
  return std::max(waves_.empty() ? 0.0 : roughnessAt(x, y), shapes);
}

double Terrain::slopeAt(double x, double y) const {
  // Per axis the gentler of the two one-sided differences: on a crease or on the edge of a
  // step lower than max_step_m the point reads the flatter side, not the jump. Samples stay
  // inside the extent (outside it the height is not the terrain's).
  const double h0 = heightAt(x, y);
  const auto gentler = [&](double xa, double ya, double xb, double yb) {
    double best = std::numeric_limits<double>::infinity();
    if (contains(xa, ya)) best = std::min(best, std::abs(heightAt(xa, ya) - h0) / kSlopeStep_m);
    if (contains(xb, yb)) best = std::min(best, std::abs(heightAt(xb, yb) - h0) / kSlopeStep_m);
    return std::isfinite(best) ? best : 0.0;
  };
  const double gx = gentler(x + kSlopeStep_m, y, x - kSlopeStep_m, y);
  const double gy = gentler(x, y + kSlopeStep_m, x, y - kSlopeStep_m);
  return std::atan(std::hypot(gx, gy));
}

double Terrain::maxHeight() const { return max_height_m_; }

double Terrain::jumpAcross(const Segment& seg, const Eigen::Vector2d& q, bool& valid) const {
  const Eigen::Vector2d d = seg.b - seg.a;
  const Eigen::Vector2d n = Eigen::Vector2d(-d.y(), d.x()).normalized() * kAcross_m;
  const Eigen::Vector2d q1 = q + n, q2 = q - n;
  // An edge on the border of the extent has the undefined outside on one side.
  valid = contains(q1.x(), q1.y()) && contains(q2.x(), q2.y());
  if (!valid) return 0.0;
  return std::abs(heightAt(q1.x(), q1.y()) - heightAt(q2.x(), q2.y()));
}

bool Terrain::jumpAlong(const Segment& seg, const Eigen::Vector2d& p, double radius_m) const {
  const Eigen::Vector2d d = seg.b - seg.a;
  const double len2 = d.squaredNorm();
  if (len2 <= 0) return false;
  const double len = std::sqrt(len2);
  const double proj = (p - seg.a).dot(d) / len2;  // unclamped parameter of the foot
  const double perp2 = std::max(0.0, (p - seg.a).squaredNorm() - proj * proj * len2);
  if (perp2 > radius_m * radius_m) return false;
  // The part of the segment within radius_m of p.
  const double half = std::sqrt(radius_m * radius_m - perp2) / len;
  const double s_lo = std::max(0.0, proj - half), s_hi = std::min(1.0, proj + half);
  if (s_lo > s_hi) return false;
  const auto exceeds = [&](double s) {
    bool valid = false;
    const double jump = jumpAcross(seg, seg.a + s * d, valid);
    return valid && jump > truth_.max_step_m;
  };
  // The ends of the interval and the foot catch jumps that grow along the edge (ramp sides);
  // the probes between catch a jump confined to part of it (a partly covered edge).
  if (exceeds(s_lo) || exceeds(s_hi) || exceeds(std::clamp(proj, s_lo, s_hi))) return true;
  const double ds = kEdgeProbe_m / len;
  for (double s = s_lo + ds; s < s_hi; s += ds) {
    if (exceeds(s)) return true;
  }
  return false;
}

core::Label Terrain::truthAt(double x, double y) const {
  if (!contains(x, y)) return core::Label::Unknown;
  const Eigen::Vector2d p(x, y);
  const double border = truth_.border_m;
  const auto& near = cell_near_shapes_[cellOf(x, y)];
  bool on_small_rock = false;
  for (std::uint32_t id : near) {
    const Shape& s = shapes_[id];
    const double dx = x - s.origin.x(), dy = y - s.origin.y();
    const double u = s.cos_yaw * dx + s.sin_yaw * dy;
    const double v = -s.sin_yaw * dx + s.cos_yaw * dy;
    if (s.kind == Shape::Kind::Ditch || (s.kind == Shape::Kind::Box && s.wall)) {
      const double du = std::max({s.u_min - u, 0.0, u - s.u_max});
      const double dv = std::max(std::abs(v) - s.v_half, 0.0);
      if (du * du + dv * dv <= border * border) return core::Label::NonTraversable;
    } else if (s.kind == Shape::Kind::Rock) {
      if (s.height_m > truth_.max_step_m) {
        const double ru = s.radius_u_m + border, rv = s.radius_v_m + border;
        if ((u / ru) * (u / ru) + (v / rv) * (v / rv) <= 1.0) return core::Label::NonTraversable;
      } else if ((u / s.radius_u_m) * (u / s.radius_u_m) +
                     (v / s.radius_v_m) * (v / s.radius_v_m) <=
                 1.0) {
        on_small_rock = true;
      }
    }
  }
  for (std::uint32_t id : near) {
    for (const Segment& seg : edges_[id]) {
      if (jumpAlong(seg, p, border)) return core::Label::NonTraversable;
    }
  }
  if (on_small_rock) return core::Label::Traversable;
  if (slopeAt(x, y) > truth_.max_slope_rad) return core::Label::NonTraversable;
  return core::Label::Traversable;
}

}  // namespace upd::sim
