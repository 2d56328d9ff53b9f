// A synthetic 2.5D world with exact ground truth: what the scene generator samples, the
// simulated depth camera ray-casts and the robot simulator drives on.
//
// Frame: z up, metres. The surface is a height field over a rectangular extent: flat ground at
// z = 0 (optionally with a smooth random roughness), plus primitives. Raised primitives (Ramp,
// Box, Rock, Stairs) stand on z = 0 and the highest one wins; a Ditch cuts its flat floor below
// everything else inside its footprint. Where primitives end the height jumps, so the surface
// has true vertical faces (risers, walls, ditch walls); the ray caster hits them and
// sampleSurface() samples them. Outside the extent the world is the plane z = 0 and its truth
// is Unknown.
//
// Ground truth (truthAt) answers "could a small rover (the Dune, upd/sim/robot.h) stand here?"
// by a local rule, evaluated in this order:
//  1. outside the extent: Unknown;
//  2. NonTraversable inside a ditch or within border_m of it (floor, walls and both rims);
//  3. NonTraversable on a wall Box (Box::wall) or within border_m of it;
//  4. NonTraversable on a rock taller than max_step_m: inside its ellipse with both radii grown
//     by border_m (its foot is vertical, a wheel cannot climb it);
//  5. NonTraversable within border_m (horizontal distance) of a vertical discontinuity of the
//     height taller than max_step_m, on both sides: the edge of a step, platform, stair riser,
//     the sides of a ramp where they stand taller than max_step_m;
//  6. Traversable on a rock no taller than max_step_m (the wheels roll over it);
//  7. NonTraversable where the surface slope exceeds max_slope_rad;
//  8. Traversable otherwise: flat or rough ground, ramp bodies and the concave line at their
//     foot, platform and stair-tread tops away from their edges.
// The rule is local: the top of a platform is Traversable even if only a ramp leads there.
#pragma once

#include "upd/core/params.h"
#include "upd/core/point_cloud.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace upd::sim {

/// Ground-truth thresholds for a small rover.
struct TruthParams {
  double max_slope_rad = 25.0 * core::kDegToRad;  ///< steeper surfaces are non-traversable [rad]
  double max_step_m = 0.05;  ///< taller vertical discontinuities are non-traversable [m]
  double border_m = 0.05;    ///< band around such discontinuities, both sides [m]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v.angleDeg("max_slope_deg", max_slope_rad, "steeper surfaces are non-traversable [deg]");
    v("max_step_m", max_step_m, "taller vertical discontinuities are non-traversable [m]");
    v("border_m", border_m, "non-traversable band around such discontinuities [m]");
  }
};

/// A straight ramp: starts at ground level on a line through start_xy perpendicular to yaw,
/// rises along yaw at slope_rad up to height_m (horizontal length height_m / tan(slope_rad)),
/// then stays flat for platform_length_m. Its sides are vertical faces.
struct Ramp {
  Eigen::Vector2d start_xy = Eigen::Vector2d::Zero();  ///< centre of the lower edge [m]
  double yaw_rad = 0.0;                                ///< direction of ascent from +x [rad]
  double slope_rad = 20.0 * core::kDegToRad;                 ///< (0, 60 deg] [rad]
  double width_m = 1.5;                                ///< across the direction of ascent [m]
  double height_m = 0.3;                               ///< height at the top of the slope [m]
  double platform_length_m = 0.0;                      ///< flat top beyond the slope, may be 0 [m]

  double slopeLength() const;  ///< horizontal length of the sloped part [m]
  void validate() const;
};

/// A raised block with a flat top: a step, a platform or (wall = true) a wall.
struct Box {
  Eigen::Vector2d center_xy = Eigen::Vector2d::Zero();  ///< [m]
  double length_m = 1.0;                                ///< along yaw [m]
  double width_m = 1.0;                                 ///< across yaw [m]
  double height_m = 0.15;                               ///< top above z = 0 [m]
  double yaw_rad = 0.0;                                 ///< [rad]
  bool wall = false;  ///< the top is not drivable either (truth rule 3)

  void validate() const;
};

/// A rectangular trench with a flat floor at -depth_m and vertical walls.
struct Ditch {
  Eigen::Vector2d center_xy = Eigen::Vector2d::Zero();  ///< [m]
  double length_m = 2.0;                                ///< along yaw [m]
  double width_m = 0.5;                                 ///< across yaw [m]
  double depth_m = 0.3;                                 ///< floor below z = 0 [m]
  double yaw_rad = 0.0;                                 ///< [rad]

  void validate() const;
};

/// A half-ellipsoid bump: z = height_m * sqrt(1 - (u/radius_x_m)^2 - (v/radius_y_m)^2) in the
/// frame rotated by yaw_rad about center_xy.
struct Rock {
  Eigen::Vector2d center_xy = Eigen::Vector2d::Zero();  ///< [m]
  double radius_x_m = 0.25;                             ///< along yaw [m]
  double radius_y_m = 0.25;                             ///< across yaw [m]
  double height_m = 0.2;                                ///< [m]
  double yaw_rad = 0.0;                                 ///< [rad]

  void validate() const;
};

/// A flight of steps: step k (0-based) covers [k run_m, (k+1) run_m) along yaw from the start
/// line and stands (k+1) rise_m high; the top step continues for top_length_m.
struct Stairs {
  Eigen::Vector2d start_xy = Eigen::Vector2d::Zero();  ///< centre of the first riser [m]
  double yaw_rad = 0.0;                                ///< direction of ascent [rad]
  double width_m = 1.5;                                ///< [m]
  int steps = 3;                                       ///< >= 1
  double rise_m = 0.15;                                ///< [m]
  double run_m = 0.3;                                  ///< tread depth [m]
  double top_length_m = 0.0;                           ///< extra length of the top step [m]

  void validate() const;
};

/// Smooth random ground relief: a sum of 8 plane waves with random directions, phases and
/// wavelengths in [0.5, 1.5] wavelength_m, scaled so the height has RMS rms_height_m. Its
/// magnitude never exceeds 4 rms_height_m.
struct Roughness {
  double rms_height_m = 0.0;  ///< 0 = perfectly flat ground [m]
  double wavelength_m = 0.5;  ///< mean wavelength [m]
  int seed = 1;               ///< >= 0

  void validate() const;
};

/// Points sampled on the surface with their truth: the first surface_points are the top
/// surface on the grid, the rest lie on vertical faces.
struct SurfaceSamples {
  core::PointCloud cloud;
  std::vector<core::Label> truth;
  std::size_t surface_points = 0;
};

class Terrain {
 public:
  /// Flat ground over x, y in [-5, 5].
  Terrain() : Terrain(Eigen::Vector2d(-5.0, -5.0), Eigen::Vector2d(5.0, 5.0)) {}
  /// An empty world (flat ground) over [min_xy, max_xy]; throws std::invalid_argument for an
  /// empty or non-finite extent or bad truth parameters.
  Terrain(const Eigen::Vector2d& min_xy, const Eigen::Vector2d& max_xy,
          const TruthParams& truth = TruthParams{});

  /// Each add validates the primitive (std::invalid_argument naming the field) and returns
  /// *this so worlds read as a list.
  Terrain& add(const Ramp& p);
  Terrain& add(const Box& p);
  Terrain& add(const Ditch& p);
  Terrain& add(const Rock& p);
  Terrain& add(const Stairs& p);
  Terrain& setRoughness(const Roughness& r);
  Terrain& setTruthParams(const TruthParams& t);

  const Eigen::Vector2d& minXY() const { return min_xy_; }
  const Eigen::Vector2d& maxXY() const { return max_xy_; }
  const TruthParams& truthParams() const { return truth_; }
  const Roughness& roughness() const { return roughness_; }
  const std::vector<Ramp>& ramps() const { return ramps_; }
  const std::vector<Box>& boxes() const { return boxes_; }
  const std::vector<Ditch>& ditches() const { return ditches_; }
  const std::vector<Rock>& rocks() const { return rocks_; }
  const std::vector<Stairs>& stairs() const { return stairs_; }

  /// True inside the closed extent.
  bool contains(double x, double y) const;
  /// Surface height [m]; 0 outside the extent.
  double heightAt(double x, double y) const;
  /// Surface slope [rad] from 1e-4 m finite differences, per axis the gentler side: a crease or
  /// the edge of a low step reads its flatter side.
  double slopeAt(double x, double y) const;
  /// Truth by the rule in the header comment.
  core::Label truthAt(double x, double y) const;
  /// Upper bound of the height anywhere [m].
  double maxHeight() const;

  /// First intersection of the ray origin + t dir (dir need not be unit; t in [0, max_range_m]
  /// measured along dir normalized) with the surface, vertical faces included; nullopt when the
  /// ray leaves the range first or starts below the surface. Precise to about 1e-6 m.
  std::optional<Eigen::Vector3d> raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                         double max_range_m) const;

  /// Grid points every spacing_m over the extent (from min_xy, (nx+1) x (ny+1) with
  /// nx = floor(extent_x / spacing_m)) at heightAt, then points on every vertical face: along
  /// each discontinuity every spacing_m, at heights bottom + k spacing_m strictly below the top.
  /// Face points are NonTraversable when the face is taller than max_step_m, else truthAt.
  /// Throws std::invalid_argument for spacing_m <= 0.
  SurfaceSamples sampleSurface(double spacing_m) const;

 private:
  /// A primitive in its local frame: u along yaw from origin, v to the left of it.
  struct Shape {
    enum class Kind : std::uint8_t { Ramp, Box, Ditch, Rock, Stairs };
    Kind kind = Kind::Box;
    Eigen::Vector2d origin = Eigen::Vector2d::Zero();
    double cos_yaw = 1.0, sin_yaw = 0.0;
    double u_min = 0.0, u_max = 0.0, v_half = 0.0;  ///< footprint rectangle (rock: bounds)
    double height_m = 0.0;  ///< top; ditch: floor (negative); stairs: rise per step
    double max_height_m = 0.0;
    double tan_slope = 0.0;                     ///< ramp
    double radius_u_m = 0.0, radius_v_m = 0.0;  ///< rock
    double run_m = 0.0;                         ///< stairs
    int steps = 0;                              ///< stairs
    bool wall = false;
  };
  struct Segment {
    Eigen::Vector2d a, b;
  };
  struct Ray;  // terrain_raycast.cpp
  std::optional<Eigen::Vector3d> walkCells(const Ray& ray, double t_in, double t_out,
                                           bool& to_sky) const;
  std::optional<Eigen::Vector3d> marchCell(const Ray& ray, double t, double t_end, double bound,
                                           double march_dt, double slope_bound,
                                           double& t_above) const;
  static Shape orientedShape(const Eigen::Vector2d& origin, double yaw_rad);
  void addShape(const Shape& s);
  void rebuildIndex();
  void indexShape(std::size_t shape_index);
  std::size_t cellOf(double x, double y) const;
  double roughnessAt(double x, double y) const;
  double shapeHeight(const Shape& s, double x, double y, bool& inside) const;
  std::vector<Segment> shapeEdges(const Shape& s) const;
  bool jumpAlong(const Segment& seg, const Eigen::Vector2d& p, double radius_m) const;
  double jumpAcross(const Segment& seg, const Eigen::Vector2d& q, bool& valid) const;

  Eigen::Vector2d min_xy_, max_xy_;
  TruthParams truth_;
  Roughness roughness_;
  std::vector<Ramp> ramps_;
  std::vector<Box> boxes_;
  std::vector<Ditch> ditches_;
  std::vector<Rock> rocks_;
  std::vector<Stairs> stairs_;

  std::vector<Shape> shapes_;
  std::vector<std::vector<Segment>> edges_;  ///< per shape, world frame
  // Plane waves of the roughness: unit direction scaled by 2 pi / wavelength, phase, amplitude.
  std::vector<Eigen::Vector4d> waves_;
  double roughness_bound_m_ = 0.0;
  double roughness_gradient_bound_ = 0.0;  ///< sum of amplitude x wavenumber: |grad h| <= this
  // Uniform grid over the extent: per cell the shapes whose footprint touches it (heights),
  // those within border_m of it (truth), an upper bound of the height (ray skipping) and one of
  // the slope (cell_slope_).
  double cell_m_ = 0.25, inv_cell_ = 4.0;
  double max_height_m_ = 0.0;
  int nx_ = 1, ny_ = 1;
  std::vector<std::vector<std::uint32_t>> cell_shapes_, cell_near_shapes_;
  std::vector<double> cell_max_m_;
  // Per cell an upper bound of the surface's slope |grad h| (infinity where an edge or a rock
  // makes it unbounded): the ray caster's step length.
  std::vector<double> cell_slope_;
};

/// A named world for simulation: terrain, default start pose and goal.
struct WorldSpec {
  Terrain terrain;
  Eigen::Vector3d start_xy_yaw;  ///< start pose (x [m], y [m], yaw [rad])
  Eigen::Vector2d goal_xy;       ///< goal position [m]
  std::string description;
  /// A closed course (may be empty): a route drives start, these in order, back to start (the
  /// goal is the first of them); runs longer than one lap repeat it.
  std::vector<Eigen::Vector2d> course = {};
};

/// The names makeWorld accepts: "mixed", "rocks", "ramp", "ditch", "corridor", "trapped",
/// "loop".
std::vector<std::string> worldNames();

/// Builds a named world (default TruthParams). Every solvable world leaves 0.42 m of clearance
/// (the Dune's circumscribed radius) along some path from start to goal. Layouts [m]:
///  mixed     x 0..12, y -4..4, flat. A 20 deg ramp (1.5 m wide, |y + 2.5| <= 0.75) from
///            x = 3 onto a 0.3 m platform x 3.82..5.82, y -3.5..-1.5; rocks 0.15, 0.3, 0.2 m
///            high at (5, 1.2), (7, 2.2), (9, 1.6) and a 4 cm pebble at (3, 1); a 0.15 m step
///            x 9..10.5, y -3.25..-1.75; a ditch 0.6 m wide, 0.3 m deep, x 6.95..7.55,
///            y -3.8..-0.8. Start (1, 0, 0), goal (11, 0.5): an open lane along y = 0.
///  rocks     x 0..10, y -3..3, rough ground (RMS 5 mm). Rocks 0.15-0.3 m high, ~0.3 m
///            radius, in rows at x = 3.5 and 6.9 (y = -2.4, 0, 2.4) and x = 5.2 (y = +-1.2):
///            1.7 m gaps, no straight way; four 3-4 cm pebbles. Start (1, 0, 0), goal (9, 0).
///  ramp      x 0..10, y -4..4. A 0.3 m platform x 5..9, y -1..2 with the goal (7, 0.5) on
///            top; its only access is a 20 deg ramp 1.6 m wide (x 7.2..8.8) climbing +y from
///            y = -1.82 to its south edge; every other edge is a 0.3 m drop. Start (1, 0, 0).
///  ditch     x 0..10, y -4..4. A ditch 0.6 m wide, 0.3 m deep along x = 5 (x 4.7..5.3) from
///            beyond the south border to y = 2.2; the way round is the 1.8 m gap north of it.
///            Start (1, -1, 0), goal (9, -1).
///  corridor  x 0..12, y -3..3. Walls 0.8 m high along y = +-1.575 for x 2..10 (inner faces
///            at +-1.5), joined to the borders by cross walls at x = 2 and x = 10, so the
///            corridor is the only way through; inside, two 0.15 m steps overlap across the
///            middle (x 4.6..5.4 for y < 0.15 and x 7.1..7.9 for y > -0.15), a chicane with
///            1.65 m passages. Start (1, 0, 0), goal (11, 0).
///  trapped   x 0..10, y -4..4. The goal (7, 0) is inside a closed square of 0.8 m walls
///            (outside 2.4 m, 0.15 m thick): unreachable. Start (1, 0, 0).
///  loop      x 0..60, y 0..30, flat. A closed course (WorldSpec::course) round the rectangle
///            (5, 5), (55, 5), (55, 25), (5, 25): 140 m a lap, for long runs. Every 5 m along
///            each side, 1.6 m left or right of the lane in turn: a 0.25 m rock, a 0.6 m
///            square 0.15 m step, a 0.3 m rock, a 1.5 x 0.5 m ditch 0.3 m deep along the lane;
///            every 7 m a 4 cm pebble 0.5 m left of the lane centre. Start (5, 5, 0).
/// Throws std::invalid_argument listing the valid names for an unknown name.
WorldSpec makeWorld(const std::string& name);

}  // namespace upd::sim
