#include "upd/core/terrain.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace upd {

namespace {

constexpr double kPi = 3.14159265358979323846;
// Offset across an edge to read the height on either side of it [m]: far below any feature
// size, far above the rounding of rotated coordinates.
constexpr double kAcross_m = 1e-6;
// Spacing of the samples along an edge when looking for a discontinuity near a point [m].
constexpr double kEdgeProbe_m = 0.005;
// Horizontal step of the ray march inside a cell that may be hit [m]: thinner features than
// this could be stepped over; every primitive of the worlds is at least 10x wider.
constexpr double kMarchStep_m = 0.01;
// Ray parameter tolerance of the bisection [m] and height tolerance of a hit [m].
constexpr double kBisectTol_m = 1e-7;
constexpr double kSurfaceTol_m = 1e-9;
// Finite-difference step of the slope [m]: small so a step below max_step_m does not read as
// a steep slope except within this distance of it.
constexpr double kSlopeStep_m = 1e-4;

bool finite(const Eigen::Vector2d& v) { return std::isfinite(v.x()) && std::isfinite(v.y()); }

}  // namespace

// ----------------------------------------------------------------------------- validation

void TruthParams::validate() const {
  requireParam(std::isfinite(max_slope_rad) && max_slope_rad > 0 && max_slope_rad < kPi / 2,
               "TruthParams", "max_slope_rad", max_slope_rad, "must be in (0, pi/2)");
  requireParam(std::isfinite(max_step_m) && max_step_m > 0, "TruthParams", "max_step_m", max_step_m,
               "must be > 0");
  requireParam(std::isfinite(border_m) && border_m >= 0, "TruthParams", "border_m", border_m,
               "must be >= 0");
}

double Ramp::slopeLength() const { return height_m / std::tan(slope_rad); }

void Ramp::validate() const {
  requireParam(finite(start_xy), "Ramp", "start_xy", start_xy.transpose(), "must be finite");
  requireParam(std::isfinite(yaw_rad), "Ramp", "yaw_rad", yaw_rad, "must be finite");
  requireParam(std::isfinite(slope_rad) && slope_rad > 0 && slope_rad <= 60.0 * kDegToRad, "Ramp",
               "slope_rad", slope_rad, "must be in (0, 60 deg]");
  requireParam(std::isfinite(width_m) && width_m > 0, "Ramp", "width_m", width_m, "must be > 0");
  requireParam(std::isfinite(height_m) && height_m > 0, "Ramp", "height_m", height_m,
               "must be > 0");
  requireParam(std::isfinite(platform_length_m) && platform_length_m >= 0, "Ramp",
               "platform_length_m", platform_length_m, "must be >= 0");
}

void Box::validate() const {
  requireParam(finite(center_xy), "Box", "center_xy", center_xy.transpose(), "must be finite");
  requireParam(std::isfinite(length_m) && length_m > 0, "Box", "length_m", length_m, "must be > 0");
  requireParam(std::isfinite(width_m) && width_m > 0, "Box", "width_m", width_m, "must be > 0");
  requireParam(std::isfinite(height_m) && height_m > 0, "Box", "height_m", height_m, "must be > 0");
  requireParam(std::isfinite(yaw_rad), "Box", "yaw_rad", yaw_rad, "must be finite");
}

void Ditch::validate() const {
  requireParam(finite(center_xy), "Ditch", "center_xy", center_xy.transpose(), "must be finite");
  requireParam(std::isfinite(length_m) && length_m > 0, "Ditch", "length_m", length_m,
               "must be > 0");
  requireParam(std::isfinite(width_m) && width_m > 0, "Ditch", "width_m", width_m, "must be > 0");
  requireParam(std::isfinite(depth_m) && depth_m > 0, "Ditch", "depth_m", depth_m, "must be > 0");
  requireParam(std::isfinite(yaw_rad), "Ditch", "yaw_rad", yaw_rad, "must be finite");
}

void Rock::validate() const {
  requireParam(finite(center_xy), "Rock", "center_xy", center_xy.transpose(), "must be finite");
  requireParam(std::isfinite(radius_x_m) && radius_x_m > 0, "Rock", "radius_x_m", radius_x_m,
               "must be > 0");
  requireParam(std::isfinite(radius_y_m) && radius_y_m > 0, "Rock", "radius_y_m", radius_y_m,
               "must be > 0");
  requireParam(std::isfinite(height_m) && height_m > 0, "Rock", "height_m", height_m,
               "must be > 0");
  requireParam(std::isfinite(yaw_rad), "Rock", "yaw_rad", yaw_rad, "must be finite");
}

void Stairs::validate() const {
  requireParam(finite(start_xy), "Stairs", "start_xy", start_xy.transpose(), "must be finite");
  requireParam(std::isfinite(yaw_rad), "Stairs", "yaw_rad", yaw_rad, "must be finite");
  requireParam(std::isfinite(width_m) && width_m > 0, "Stairs", "width_m", width_m, "must be > 0");
  requireParam(steps >= 1, "Stairs", "steps", steps, "must be >= 1");
  requireParam(std::isfinite(rise_m) && rise_m > 0, "Stairs", "rise_m", rise_m, "must be > 0");
  requireParam(std::isfinite(run_m) && run_m > 0, "Stairs", "run_m", run_m, "must be > 0");
  requireParam(std::isfinite(top_length_m) && top_length_m >= 0, "Stairs", "top_length_m",
               top_length_m, "must be >= 0");
}

void Roughness::validate() const {
  requireParam(std::isfinite(rms_height_m) && rms_height_m >= 0, "Roughness", "rms_height_m",
               rms_height_m, "must be >= 0");
  requireParam(std::isfinite(wavelength_m) && wavelength_m > 0, "Roughness", "wavelength_m",
               wavelength_m, "must be > 0");
  requireParam(seed >= 0, "Roughness", "seed", seed, "must be >= 0");
}

// ----------------------------------------------------------------------------- construction

Terrain::Terrain(const Eigen::Vector2d& min_xy, const Eigen::Vector2d& max_xy,
                 const TruthParams& truth)
    : min_xy_(min_xy), max_xy_(max_xy), truth_(truth) {
  requireParam(finite(min_xy), "Terrain", "min_xy", min_xy.transpose(), "must be finite");
  requireParam(finite(max_xy) && max_xy.x() > min_xy.x() && max_xy.y() > min_xy.y(), "Terrain",
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
  // 0.25 m cells, coarser for huge extents so the index stays below ~250k cells.
  cell_m_ = std::max(0.25, std::sqrt(size.x() * size.y() / 250000.0));
  inv_cell_ = 1.0 / cell_m_;
  nx_ = std::max(1, static_cast<int>(std::ceil(size.x() / cell_m_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(size.y() / cell_m_)));
  const std::size_t n = static_cast<std::size_t>(nx_) * ny_;
  cell_shapes_.assign(n, {});
  cell_near_shapes_.assign(n, {});
  cell_max_m_.assign(n, roughness_bound_m_);
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
  cover(1e-6, [&](std::size_t c) {
    cell_shapes_[c].push_back(id);
    cell_max_m_[c] = std::max(cell_max_m_[c], s.max_height_m + roughness_bound_m_);
    max_height_m_ = std::max(max_height_m_, cell_max_m_[c]);
  });
  cover(truth_.border_m + 1e-6, [&](std::size_t c) { cell_near_shapes_[c].push_back(id); });
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
  for (const Eigen::Vector4d& w : waves_) h += w[3] * std::sin(w[0] * x + w[1] * y + w[2]);
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
  double h = waves_.empty() ? 0.0 : roughnessAt(x, y);
  double ditch_floor = std::numeric_limits<double>::infinity();
  for (std::uint32_t id : cell_shapes_[cellOf(x, y)]) {
    const Shape& s = shapes_[id];
    bool inside = false;
    const double sh = shapeHeight(s, x, y, inside);
    if (!inside) continue;
    if (s.kind == Shape::Kind::Ditch) {
      ditch_floor = std::min(ditch_floor, sh);
    } else {
      h = std::max(h, sh);
    }
  }
  return std::isfinite(ditch_floor) ? ditch_floor : h;
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

Label Terrain::truthAt(double x, double y) const {
  if (!contains(x, y)) return Label::Unknown;
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
      if (du * du + dv * dv <= border * border) return Label::NonTraversable;
    } else if (s.kind == Shape::Kind::Rock) {
      if (s.height_m > truth_.max_step_m) {
        const double ru = s.radius_u_m + border, rv = s.radius_v_m + border;
        if ((u / ru) * (u / ru) + (v / rv) * (v / rv) <= 1.0) return Label::NonTraversable;
      } else if ((u / s.radius_u_m) * (u / s.radius_u_m) +
                     (v / s.radius_v_m) * (v / s.radius_v_m) <=
                 1.0) {
        on_small_rock = true;
      }
    }
  }
  for (std::uint32_t id : near) {
    for (const Segment& seg : edges_[id]) {
      if (jumpAlong(seg, p, border)) return Label::NonTraversable;
    }
  }
  if (on_small_rock) return Label::Traversable;
  if (slopeAt(x, y) > truth_.max_slope_rad) return Label::NonTraversable;
  return Label::Traversable;
}

// ----------------------------------------------------------------------------- ray casting

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
  const Eigen::Vector3d d = dir / dir_norm;
  const Eigen::Vector3d& o = origin;
  const auto point = [&](double t) -> Eigen::Vector3d { return o + t * d; };
  const auto above = [&](double t) {
    const Eigen::Vector3d p = point(t);
    return p.z() - heightAt(p.x(), p.y());
  };
  if (above(0.0) < 0.0) return std::nullopt;                       // starts under the surface
  if (d.z() >= 0.0 && o.z() > max_height_m_) return std::nullopt;  // the sky

  // Outside the extent the world is the plane z = 0.
  const auto planeHit = [&](double ta, double tb) -> std::optional<Eigen::Vector3d> {
    if (d.z() >= 0.0) return std::nullopt;
    const double t = -o.z() / d.z();
    if (t >= ta && t <= tb) return point(t);
    return std::nullopt;
  };

  // The part of the ray over the extent (slab test).
  double t_in = 0.0, t_out = max_range_m;
  for (int a = 0; a < 2; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (o[a] < min_xy_[a] || o[a] > max_xy_[a]) t_in = std::numeric_limits<double>::infinity();
      continue;
    }
    double t1 = (min_xy_[a] - o[a]) / d[a], t2 = (max_xy_[a] - o[a]) / d[a];
    if (t1 > t2) std::swap(t1, t2);
    t_in = std::max(t_in, t1);
    t_out = std::min(t_out, t2);
  }
  if (!(t_in <= t_out)) return planeHit(0.0, max_range_m);
  if (t_in > 0.0) {
    if (auto hit = planeHit(0.0, t_in)) return hit;
  }
  // Nothing can be hit while the ray is above the highest point.
  if (d.z() < 0.0 && o.z() > max_height_m_) {
    t_in = std::max(t_in, (max_height_m_ - o.z()) / d.z());
    if (t_in > t_out) return t_out < max_range_m ? planeHit(t_out, max_range_m) : std::nullopt;
  }

  // Between a parameter above the surface and one on or below it. Secant steps are exact on a
  // plane and fast on smooth relief; at a vertical face they barely move, so once a secant
  // step fails to halve the bracket only bisection follows (the hit within kBisectTol_m).
  const auto refine = [&](double lo, double hi) -> Eigen::Vector3d {
    double f_lo = above(lo), f_hi = above(hi);
    bool secant = true;
    for (int i = 0; i < 128 && hi - lo > kBisectTol_m; ++i) {
      const double width = hi - lo;
      const bool use_secant = secant && f_lo - f_hi > 0.0;
      const double t = use_secant ? lo + width * f_lo / (f_lo - f_hi) : 0.5 * (lo + hi);
      const double f = above(t);
      if (std::abs(f) <= kSurfaceTol_m) return point(t);
      if (f > 0.0) {
        lo = t;
        f_lo = f;
      } else {
        hi = t;
        f_hi = f;
      }
      if (use_secant && hi - lo > 0.5 * width) secant = false;
    }
    return point(f_lo - f_hi > 0.0 ? lo + (hi - lo) * f_lo / (f_lo - f_hi) : hi);
  };

  double t_above = t_in;
  if (above(t_in) <= 0.0) return point(t_in);  // enters through a face on the border

  // Walk the cells the ray crosses (Amanatides-Woo); skip a cell where the ray stays above its
  // height bound, otherwise march it in small horizontal steps from where it descends to the
  // bound.
  const Eigen::Vector3d p_in = point(t_in);
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

  double t = t_in;
  while (true) {
    const double t_end = std::min({t_next_x, t_next_y, t_out});
    const double bound = cell_max_m_[static_cast<std::size_t>(iy) * nx_ + ix];
    const double za = o.z() + t * d.z(), zb = o.z() + t_end * d.z();
    if (std::min(za, zb) > bound) {
      t_above = std::max(t_above, t_end);
    } else {
      double tc = t;
      if (za > bound && d.z() < 0.0) tc = std::max(t, (bound - o.z()) / d.z());
      while (true) {
        if (above(tc) <= 0.0) return refine(t_above, tc);
        t_above = tc;
        if (tc >= t_end) break;
        tc = std::min(tc + march_dt, t_end);
      }
    }
    if (t_end >= t_out) break;
    if (d.z() >= 0.0 && zb > max_height_m_) return std::nullopt;  // climbing above everything
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
  if (t_out < max_range_m) return planeHit(t_out, max_range_m);
  return std::nullopt;
}

// ----------------------------------------------------------------------------- sampling

SurfaceSamples Terrain::sampleSurface(double spacing_m) const {
  requireParam(std::isfinite(spacing_m) && spacing_m > 0, "Terrain::sampleSurface", "spacing_m",
               spacing_m, "must be > 0");
  const Eigen::Vector2d size = max_xy_ - min_xy_;
  const double nxd = std::floor(size.x() / spacing_m + 1e-9);
  const double nyd = std::floor(size.y() / spacing_m + 1e-9);
  requireParam((nxd + 1) * (nyd + 1) <= 2e8, "Terrain::sampleSurface", "spacing_m", spacing_m,
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
        const Label label =
            hi - lo > truth_.max_step_m ? Label::NonTraversable : truthAt(q.x(), q.y());
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

// ----------------------------------------------------------------------------- worlds

namespace {

constexpr double kHalfPi = 0.5 * kPi;

Box wallBox(double cx, double cy, double length_m, double width_m) {
  Box b;
  b.center_xy = {cx, cy};
  b.length_m = length_m;
  b.width_m = width_m;
  b.height_m = 0.8;
  b.wall = true;
  return b;
}

Box block(double cx, double cy, double length_m, double width_m, double height_m) {
  Box b;
  b.center_xy = {cx, cy};
  b.length_m = length_m;
  b.width_m = width_m;
  b.height_m = height_m;
  return b;
}

Rock rock(double cx, double cy, double rx, double ry, double h, double yaw = 0.0) {
  Rock r;
  r.center_xy = {cx, cy};
  r.radius_x_m = rx;
  r.radius_y_m = ry;
  r.height_m = h;
  r.yaw_rad = yaw;
  return r;
}

WorldSpec mixedWorld() {
  Terrain t({0.0, -4.0}, {12.0, 4.0});
  Ramp ramp;
  ramp.start_xy = {3.0, -2.5};
  ramp.yaw_rad = 0.0;
  ramp.slope_rad = 20.0 * kDegToRad;
  ramp.width_m = 1.5;
  ramp.height_m = 0.3;
  const double top_x = 3.0 + ramp.slopeLength();
  t.add(ramp)
      .add(block(top_x + 1.0, -2.5, 2.0, 2.0, 0.3))  // the platform the ramp leads onto
      .add(rock(5.0, 1.2, 0.25, 0.25, 0.15))
      .add(rock(7.0, 2.2, 0.35, 0.30, 0.30, 0.4))
      .add(rock(9.0, 1.6, 0.25, 0.20, 0.20, -0.3))
      .add(rock(3.0, 1.0, 0.15, 0.15, 0.04))    // small enough to drive over
      .add(block(9.75, -2.5, 1.5, 1.5, 0.15));  // a 0.15 m step
  Ditch ditch;
  ditch.center_xy = {7.25, -2.3};
  ditch.yaw_rad = kHalfPi;
  ditch.length_m = 3.0;
  ditch.width_m = 0.6;
  ditch.depth_m = 0.3;
  t.add(ditch);
  return {t,
          {1.0, 0.0, 0.0},
          {11.0, 0.5},
          "12 x 8 m flat ground: a 20 deg ramp onto a 0.3 m platform, rocks 0.15-0.3 m, a "
          "0.15 m step, a 0.6 m wide ditch; an open lane along y = 0 from start to goal"};
}

WorldSpec rocksWorld() {
  Terrain t({0.0, -3.0}, {10.0, 3.0});
  Roughness rough;
  rough.rms_height_m = 0.005;
  rough.wavelength_m = 0.8;
  rough.seed = 11;
  t.setRoughness(rough);
  // Three staggered rows: every straight line from start to goal hits a rock, gaps between
  // rocks are 1.7 m of traversable ground.
  t.add(rock(3.5, -2.4, 0.30, 0.30, 0.20))
      .add(rock(3.5, 0.0, 0.30, 0.28, 0.25, 0.3))
      .add(rock(3.5, 2.4, 0.30, 0.30, 0.18))
      .add(rock(5.2, -1.2, 0.30, 0.25, 0.30, 0.8))
      .add(rock(5.2, 1.2, 0.28, 0.28, 0.22))
      .add(rock(6.9, -2.4, 0.30, 0.30, 0.25))
      .add(rock(6.9, 0.0, 0.30, 0.30, 0.20, -0.5))
      .add(rock(6.9, 2.4, 0.30, 0.30, 0.15))
      .add(rock(2.5, 1.0, 0.12, 0.12, 0.04))
      .add(rock(4.3, -0.6, 0.12, 0.10, 0.03))
      .add(rock(6.0, 0.7, 0.12, 0.12, 0.04))
      .add(rock(7.8, -1.3, 0.10, 0.12, 0.03));
  return {t,
          {1.0, 0.0, 0.0},
          {9.0, 0.0},
          "10 x 6 m rough ground with three staggered rows of 0.15-0.3 m rocks blocking the "
          "straight line; 1.7 m gaps between them; a few 3-4 cm pebbles that can be driven over"};
}

WorldSpec rampWorld() {
  Terrain t({0.0, -4.0}, {10.0, 4.0});
  t.add(block(7.0, 0.5, 4.0, 3.0, 0.3));  // platform x in [5, 9], y in [-1, 2]
  Ramp ramp;
  ramp.slope_rad = 20.0 * kDegToRad;
  ramp.height_m = 0.3;
  ramp.width_m = 1.6;
  ramp.yaw_rad = kHalfPi;
  ramp.start_xy = {8.0, -1.0 - ramp.slopeLength()};
  t.add(ramp);
  return {t,
          {1.0, 0.0, 0.0},
          {7.0, 0.5},
          "a 0.3 m platform (x 5..9, y -1..2) with the goal on top, surrounded by 0.3 m drops "
          "except a 1.6 m wide 20 deg ramp climbing +y onto its south side at x = 8"};
}

WorldSpec ditchWorld() {
  Terrain t({0.0, -4.0}, {10.0, 4.0});
  Ditch ditch;
  ditch.center_xy = {5.0, -1.15};
  ditch.yaw_rad = kHalfPi;
  ditch.length_m = 6.7;  // y in [-4.5, 2.2]: from beyond the south border
  ditch.width_m = 0.6;
  ditch.depth_m = 0.3;
  t.add(ditch);
  return {t,
          {1.0, -1.0, 0.0},
          {9.0, -1.0},
          "a 0.6 m wide, 0.3 m deep ditch along x = 5 from the south border to y = 2.2; the "
          "way round is the 1.8 m gap to the north border"};
}

WorldSpec corridorWorld() {
  Terrain t({0.0, -3.0}, {12.0, 3.0});
  // Corridor walls along y = +-1.575 (inner faces at +-1.5) for x in [2, 10], closed to the
  // borders by cross walls at x = 2 and x = 10, so the corridor is the only way through. The
  // width leaves 1.65 m passages beside the steps: the UPD's band (about 0.35 m at d_m = 0.5)
  // on both sides plus the Dune's 0.45 m width.
  t.add(wallBox(6.0, 1.575, 8.0, 0.15))
      .add(wallBox(6.0, -1.575, 8.0, 0.15))
      .add(wallBox(2.075, 2.55, 0.15, 2.0))
      .add(wallBox(2.075, -2.55, 0.15, 2.0))
      .add(wallBox(9.925, 2.55, 0.15, 2.0))
      .add(wallBox(9.925, -2.55, 0.15, 2.0))
      // A chicane of two 0.15 m steps, overlapping across the middle of the corridor (they
      // reach under the walls so no gap is left there).
      .add(block(5.0, -0.85, 0.8, 1.4, 0.15))
      .add(block(7.5, 0.85, 0.8, 1.4, 0.15));
  return {t,
          {1.0, 0.0, 0.0},
          {11.0, 0.0},
          "a 3 m wide walled corridor (x 2..10) closed to the borders by cross walls; two "
          "0.15 m steps (x 4.6..5.4 south, x 7.1..7.9 north) overlap across the middle: a chicane "
          "with 1.65 m passages"};
}

WorldSpec trappedWorld() {
  Terrain t({0.0, -4.0}, {10.0, 4.0});
  // A closed square of walls, 2.4 m outside, around the goal.
  t.add(wallBox(7.0, 1.125, 2.4, 0.15))
      .add(wallBox(7.0, -1.125, 2.4, 0.15))
      .add(wallBox(5.875, 0.0, 0.15, 2.4))
      .add(wallBox(8.125, 0.0, 0.15, 2.4));
  return {t,
          {1.0, 0.0, 0.0},
          {7.0, 0.0},
          "the goal (7, 0) is enclosed by a closed square of 0.8 m walls: unreachable"};
}

}  // namespace

std::vector<std::string> worldNames() {
  return {"mixed", "rocks", "ramp", "ditch", "corridor", "trapped"};
}

WorldSpec makeWorld(const std::string& name) {
  if (name == "mixed") return mixedWorld();
  if (name == "rocks") return rocksWorld();
  if (name == "ramp") return rampWorld();
  if (name == "ditch") return ditchWorld();
  if (name == "corridor") return corridorWorld();
  if (name == "trapped") return trappedWorld();
  std::string valid;
  for (const std::string& n : worldNames()) valid += (valid.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown world '" + name + "'; valid names: " + valid);
}

}  // namespace upd
