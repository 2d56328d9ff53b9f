// The named worlds of makeWorld (layouts in terrain.h).
#include "upd/sim/terrain.h"

#include "terrain_internal.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace upd::sim {

using terrain_detail::kPi;

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
  return Rock{{cx, cy}, rx, ry, h, yaw};  // centre, radii, height, yaw
}

WorldSpec mixedWorld() {
  Terrain t({0.0, -4.0}, {12.0, 4.0});
  Ramp ramp;
  ramp.start_xy = {3.0, -2.5};
  ramp.yaw_rad = 0.0;
  ramp.slope_rad = 20.0 * core::kDegToRad;
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
  ramp.slope_rad = 20.0 * core::kDegToRad;
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

// Obstacles beside one straight side of the loop from a to b: every 5 m a rock, a step, a
// taller rock or a ditch, alternately 1.6 m left and right of the lane; every 7 m a 4 cm pebble
// 0.5 m off the lane centre, which the wheels roll over.
void lineTheSide(Terrain& t, const Eigen::Vector2d& a, const Eigen::Vector2d& b, int& k) {
  const double len = (b - a).norm();
  const Eigen::Vector2d dir = (b - a) / len, left(-dir.y(), dir.x());
  const double yaw = std::atan2(dir.y(), dir.x());
  for (double s = 4.0; s <= len - 4.0; s += 5.0, ++k) {
    const Eigen::Vector2d c = a + s * dir + (k % 2 == 0 ? 1.6 : -1.6) * left;
    switch (k % 4) {
      case 0: t.add(rock(c.x(), c.y(), 0.30, 0.30, 0.25, yaw)); break;
      case 1: t.add(block(c.x(), c.y(), 0.6, 0.6, 0.15)); break;
      case 2: t.add(rock(c.x(), c.y(), 0.35, 0.25, 0.30, yaw + 0.5)); break;
      default: {
        Ditch d;
        d.center_xy = c;
        d.yaw_rad = yaw;
        d.length_m = 1.5;
        d.width_m = 0.5;
        d.depth_m = 0.3;
        t.add(d);
      }
    }
  }
  for (double s = 7.0; s <= len - 3.0; s += 7.0) {
    const Eigen::Vector2d c = a + s * dir + 0.5 * left;
    t.add(rock(c.x(), c.y(), 0.12, 0.12, 0.04));
  }
}

WorldSpec loopWorld() {
  Terrain t({0.0, 0.0}, {60.0, 30.0});
  const std::vector<Eigen::Vector2d> corners = {{5.0, 5.0}, {55.0, 5.0}, {55.0, 25.0}, {5.0, 25.0}};
  int k = 0;
  for (std::size_t c = 0; c < corners.size(); ++c) {
    lineTheSide(t, corners[c], corners[(c + 1) % corners.size()], k);
  }
  WorldSpec w{t,
              {5.0, 5.0, 0.0},
              corners[1],
              "60 x 30 m flat ground with a 140 m rectangular lap (corners (5, 5), (55, 5), "
              "(55, 25), (5, 25), anticlockwise); every 5 m beside the lane, 1.6 m left or "
              "right, a 0.25 m rock, a 0.15 m step, a 0.3 m rock or a 0.6 m wide ditch; 4 cm "
              "pebbles in the lane"};
  w.course = {corners[1], corners[2], corners[3]};
  return w;
}

}  // namespace

std::vector<std::string> worldNames() {
  return {"mixed", "rocks", "ramp", "ditch", "corridor", "trapped", "loop"};
}

WorldSpec makeWorld(const std::string& name) {
  if (name == "mixed") return mixedWorld();
  if (name == "rocks") return rocksWorld();
  if (name == "ramp") return rampWorld();
  if (name == "ditch") return ditchWorld();
  if (name == "corridor") return corridorWorld();
  if (name == "trapped") return trappedWorld();
  if (name == "loop") return loopWorld();
  std::string valid;
  for (const std::string& n : worldNames()) valid += (valid.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown world '" + name + "'; valid names: " + valid);
}

}  // namespace upd::sim
