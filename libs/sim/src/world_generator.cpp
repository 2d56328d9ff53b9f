#include "upd/sim/world_generator.h"

#include "terrain_internal.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

namespace upd::sim {

using terrain_detail::kPi;

const char* toString(Difficulty d) {
  switch (d) {
    case Difficulty::Easy: return "easy";
    case Difficulty::Default: return "default";
    case Difficulty::Hard: return "hard";
  }
  return "?";
}

Difficulty parseDifficulty(const std::string& name) {
  if (name == "easy") return Difficulty::Easy;
  if (name == "default") return Difficulty::Default;
  if (name == "hard") return Difficulty::Hard;
  throw std::invalid_argument("difficulty '" + name + "': expected easy, default or hard");
}

void WorldGenParams::validate() const {
  const char* s = "WorldGenParams";
  core::requireParam(seed >= 0, s, "seed", seed, "must be >= 0");
  core::requireParam(std::isfinite(goal_distance_m) && goal_distance_m >= 4.0, s,
                     "goal_distance_m", goal_distance_m, "must be >= 4");
  core::requireParam(std::isfinite(clear_radius_m) && clear_radius_m >= 0, s, "clear_radius_m",
                     clear_radius_m, "must be >= 0");
  core::requireParam(std::isfinite(robot_width_m) && robot_width_m > 0, s, "robot_width_m",
                     robot_width_m, "must be > 0");
  core::requireParam(max_attempts >= 1, s, "max_attempts", max_attempts, "must be >= 1");
}

namespace {

constexpr double kHalfWidth_m = 4.0;      // the world spans y in [-4, 4]
constexpr double kEndMargin_m = 2.0;      // start and goal this far from the ends
constexpr double kWallThickness_m = 0.15;
constexpr double kWallHeight_m = 0.6;
constexpr double kWallKeepOut_m = 0.6;    // other features keep this far from a wall line
constexpr double kPassageMargin_m = 0.5;  // the narrowest gap: robot width plus this
constexpr double kLaneHalfWidth_m = 2.0;  // features lie this close to the straight way
constexpr int kPlacementTries = 200;

// What a difficulty puts into a world.
struct Kinds {
  int rocks, ramps, steps, ditches, passages;
  double min_gap_m, max_gap_m;  // passage widths between the wall faces
  double roughness_rms_m;
  double solvable_clearance_m;  // solvableClearance
};

Kinds kindsOf(Difficulty d, double robot_width_m) {
  switch (d) {
    case Difficulty::Easy: return {5, 1, 1, 0, 0, 0.0, 0.0, 0.003, 0.1};
    case Difficulty::Default: return {8, 1, 2, 1, 1, 1.3, 2.4, 0.006, 0.1};
    case Difficulty::Hard: break;
  }
  return {12, 2, 2, 2, 2, robot_width_m + kPassageMargin_m, 2.0, 0.012, 0.2};
}

// Draws one candidate world; nullopt when a feature found no free place.
class Builder {
 public:
  Builder(const WorldGenParams& p, int attempt)
      : p_(p), kinds_(kindsOf(p.difficulty, p.robot_width_m)) {
    std::seed_seq seq{static_cast<unsigned>(p.seed), static_cast<unsigned>(attempt), 0x5eedu};
    rng_.seed(seq);
  }

  std::optional<GeneratedWorld> build() {
    const double ys = uniform(-1.5, 1.5), yg = uniform(-1.5, 1.5);
    const double dx = std::sqrt(p_.goal_distance_m * p_.goal_distance_m - (yg - ys) * (yg - ys));
    start_ = {kEndMargin_m, ys};
    goal_ = {kEndMargin_m + dx, yg};
    x_max_ = dx + 2.0 * kEndMargin_m;
    GeneratedWorld out{{Terrain({0.0, -kHalfWidth_m}, {x_max_, kHalfWidth_m}),
                        {start_.x(), start_.y(), std::atan2(yg - ys, dx)},
                        goal_,
                        ""},
                       {},
                       1};
    Terrain& t = out.world.terrain;
    WorldFeatures& f = out.features;
    addPassages(t, f);
    for (int i = 0; i < kinds_.ditches; ++i) {
      if (!addDitch(t)) return std::nullopt;
      ++f.ditches;
    }
    for (int i = 0; i < kinds_.ramps; ++i) {
      if (!addRampBump(t, f)) return std::nullopt;
    }
    for (int i = 0; i < kinds_.steps; ++i) {
      if (!addStep(t, f)) return std::nullopt;
    }
    for (int i = 0; i < kinds_.rocks; ++i) {
      if (!addRock(t, f, i < (kinds_.rocks + 3) / 4)) return std::nullopt;
    }
    Roughness r;
    r.rms_height_m = kinds_.roughness_rms_m;
    r.wavelength_m = uniform(0.8, 1.5);
    r.seed = p_.seed;
    t.setRoughness(r);
    f.roughness_rms_m = r.rms_height_m;
    return out;
  }

 private:
  double uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng_);
  }

  // A centre for a feature of the given radius clear of start, goal and the wall lines: near
  // the straight way from start to goal (within kLaneHalfWidth_m of it), where it is in the way.
  std::optional<Eigen::Vector2d> place(double radius_m) {
    const Eigen::Vector2d along = goal_ - start_;
    const Eigen::Vector2d across = Eigen::Vector2d(-along.y(), along.x()).normalized();
    for (int k = 0; k < kPlacementTries; ++k) {
      const Eigen::Vector2d c =
          start_ + uniform(0.0, 1.0) * along + uniform(-kLaneHalfWidth_m, kLaneHalfWidth_m) * across;
      const bool inside = c.x() > 0.5 && c.x() < x_max_ - 0.5 && std::abs(c.y()) < kHalfWidth_m - 0.5;
      bool ok = inside && (c - start_).norm() - radius_m >= p_.clear_radius_m &&
                (c - goal_).norm() - radius_m >= p_.clear_radius_m;
      for (double xw : walls_x_) ok = ok && std::abs(c.x() - xw) >= radius_m + kWallKeepOut_m;
      if (ok) return c;
    }
    return std::nullopt;
  }

  void addPassages(Terrain& t, WorldFeatures& f) {
    // Wall lines spread evenly between start and goal, each with one gap somewhere across.
    const double x0 = start_.x() + p_.clear_radius_m + 1.0, x1 = goal_.x() - p_.clear_radius_m - 1.0;
    for (int i = 0; i < kinds_.passages; ++i) {
      const double xw = x0 + (x1 - x0) * (i + 1.0) / (kinds_.passages + 1.0) + uniform(-0.5, 0.5);
      const double gap = uniform(kinds_.min_gap_m, kinds_.max_gap_m);
      const double yc = uniform(-2.5, 2.5);
      const double lo = -kHalfWidth_m - 0.5, hi = kHalfWidth_m + 0.5;  // beyond the borders
      const double a = yc - 0.5 * gap, b = yc + 0.5 * gap;
      for (const auto& [y0, y1] : {std::pair{lo, a}, std::pair{b, hi}}) {
        Box w;
        w.center_xy = {xw, 0.5 * (y0 + y1)};
        w.length_m = kWallThickness_m;
        w.width_m = y1 - y0;
        w.height_m = kWallHeight_m;
        w.wall = true;
        t.add(w);
      }
      walls_x_.push_back(xw);
      ++f.passages;
      f.narrowest_passage_m = f.passages == 1 ? gap : std::min(f.narrowest_passage_m, gap);
    }
  }

  bool addDitch(Terrain& t) {
    Ditch d;
    d.length_m = uniform(1.0, 3.0);
    d.width_m = uniform(0.3, 0.8);
    d.depth_m = uniform(0.2, 0.4);
    d.yaw_rad = uniform(0.0, kPi);
    const auto c = place(0.5 * std::hypot(d.length_m, d.width_m));
    if (!c) return false;
    d.center_xy = *c;
    t.add(d);
    return true;
  }

  // A ramp up, a flat top and a ramp down: the top is reachable over either ramp only.
  bool addRampBump(Terrain& t, WorldFeatures& f) {
    Ramp up;
    up.slope_rad = uniform(12.0, 32.0) * core::kDegToRad;
    up.height_m = uniform(0.15, 0.35);
    up.width_m = uniform(1.0, 2.0);
    up.yaw_rad = uniform(-kPi, kPi);
    const double top = uniform(0.5, 1.5);
    const double length = 2.0 * up.slopeLength() + top;
    const auto c = place(0.5 * std::hypot(length, up.width_m));
    if (!c) return false;
    const Eigen::Vector2d dir(std::cos(up.yaw_rad), std::sin(up.yaw_rad));
    up.start_xy = *c - 0.5 * length * dir;
    up.platform_length_m = top;
    Ramp down = up;
    down.start_xy = *c + 0.5 * length * dir;
    down.yaw_rad = up.yaw_rad + kPi;
    down.platform_length_m = top;
    t.add(up).add(down);
    ++f.ramps;
    f.ramps_too_steep += up.slope_rad > t.truthParams().max_slope_rad ? 1 : 0;
    return true;
  }

  bool addStep(Terrain& t, WorldFeatures& f) {
    Box b;
    b.length_m = uniform(0.8, 2.0);
    b.width_m = uniform(0.8, 2.0);
    b.yaw_rad = uniform(0.0, kPi);
    const bool drivable = uniform(0.0, 1.0) < 0.4;
    const double step = t.truthParams().max_step_m;
    b.height_m = drivable ? uniform(0.4 * step, 0.9 * step) : uniform(0.08, 0.2);
    const auto c = place(0.5 * std::hypot(b.length_m, b.width_m));
    if (!c) return false;
    b.center_xy = *c;
    t.add(b);
    ++f.steps;
    f.steps_drivable += drivable ? 1 : 0;
    return true;
  }

  // Pebbles below the step limit (driven over), the rest from just above it to 0.35 m.
  bool addRock(Terrain& t, WorldFeatures& f, bool pebble) {
    Rock r;
    const double step = t.truthParams().max_step_m;
    r.radius_x_m = pebble ? uniform(0.08, 0.2) : uniform(0.12, 0.4);
    r.radius_y_m = pebble ? uniform(0.08, 0.2) : uniform(0.12, 0.4);
    r.height_m = pebble ? uniform(0.4 * step, 0.9 * step) : uniform(1.2 * step, 0.35);
    r.yaw_rad = uniform(0.0, kPi);
    const auto c = place(std::max(r.radius_x_m, r.radius_y_m));
    if (!c) return false;
    r.center_xy = *c;
    t.add(r);
    ++f.rocks;
    f.rocks_drivable += pebble ? 1 : 0;
    return true;
  }

  const WorldGenParams& p_;
  Kinds kinds_;
  std::mt19937 rng_;
  Eigen::Vector2d start_, goal_;
  double x_max_ = 0.0;
  std::vector<double> walls_x_;
};

std::string describe(const WorldGenParams& p, const WorldFeatures& f) {
  std::string s = "generated world seed " + std::to_string(p.seed) + " (" +
                  toString(p.difficulty) + "): " + std::to_string(f.rocks) + " rocks (" +
                  std::to_string(f.rocks_drivable) + " drivable), " + std::to_string(f.ramps) +
                  " ramps (" + std::to_string(f.ramps_too_steep) + " too steep), " +
                  std::to_string(f.steps) + " steps (" + std::to_string(f.steps_drivable) +
                  " drivable), " + std::to_string(f.ditches) + " ditches, " +
                  std::to_string(f.passages) + " passages";
  if (f.passages > 0) {
    const int cm = static_cast<int>(std::lround(100.0 * f.narrowest_passage_m));
    s += " (narrowest " + std::to_string(cm) + " cm)";
  }
  return s;
}

}  // namespace

double solvableClearance(Difficulty d) { return kindsOf(d, 0.0).solvable_clearance_m; }

GeneratedWorld generateWorld(const WorldGenParams& params, const SolvableCheck& solvable) {
  params.validate();
  for (int attempt = 0; attempt < params.max_attempts; ++attempt) {
    std::optional<GeneratedWorld> w = Builder(params, attempt).build();
    if (!w || (solvable && !solvable(w->world))) continue;
    w->attempts = attempt + 1;
    w->world.description = describe(params, w->features);
    return *w;
  }
  throw std::runtime_error("world seed " + std::to_string(params.seed) + " (" +
                           toString(params.difficulty) + "): no solvable world in " +
                           std::to_string(params.max_attempts) + " attempts");
}

}  // namespace upd::sim
