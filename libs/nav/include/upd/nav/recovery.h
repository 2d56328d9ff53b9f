// Recovery of a stalled robot. MRPT's reactive navigator stops (or swings back and forth on the
// spot) when every one of its PTG paths meets an obstacle within its safety distances: beside a
// rock after a tight turn, at the mouth of a gap, on a ramp between its sides. Its PTGs have no
// turn in place and it does not back out, so it waits there until its no-progress timeout. The
// loop watches for such a stall (the robot has stayed within stall_radius_m for stall_time_s) and
// then drives one short manoeuvre itself, checked against the same obstacle points and robot
// shape the navigator uses: a turn in place towards the route, else a reverse (arcing towards the
// route, straight, or arcing away), after which the navigator starts again on the route.
// Turns and reverses alike stay on observed ground: unless into_unobserved, the centres of the
// map's unknown cells are checked like obstacle points. A forward-looking camera may never have
// seen the ground behind the robot, and in the field a ditch or a rock there is as likely as
// anywhere else; a reverse onto it would be the one motion of the robot that no sensor checked.
// Unknown cells under the robot's shape are left out: the robot stands on that ground (and the
// loop leaves out every cell the shape has covered on the way: the robot stood there too).
#pragma once

#include "upd/nav/robot_base.h"

#include <Eigen/Core>

#include <vector>

namespace upd::nav {

/// Loaded from [RecoveryParams].
struct RecoveryParams {
  bool enabled = true;               ///< watch for stalls and recover
  double stall_time_s = 5.0;         ///< a stall: this long ...
  double stall_radius_m = 0.25;      ///< ... within this distance of one spot [m]
  int max_recoveries = 6;            ///< per navigation (then the navigator's own timeout ends it)
  double turn_rate_radps = 0.5;      ///< turn in place at this rate [rad/s]
  double max_turn_rad = 1.6;         ///< turn at most this far in one manoeuvre [rad]
  double min_turn_rad = 0.35;        ///< a shorter feasible turn is not worth it [rad]
  double reverse_speed_mps = 0.15;   ///< reverse at this speed [m/s]
  double reverse_turn_radps = 0.35;  ///< turn rate of the reversing arcs [rad/s]
  double reverse_distance_m = 0.4;   ///< reverse at most this far [m]
  double min_reverse_m = 0.1;        ///< a shorter feasible reverse is not worth it [m]
  bool into_unobserved = false;      ///< may drive onto ground the map has not observed

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("enabled", enabled, "watch for a stalled robot and drive a recovery manoeuvre");
    v("stall_time_s", stall_time_s, "a stall: the robot stayed this long ... [s]");
    v("stall_radius_m", stall_radius_m, "... within this distance of one spot [m]");
    v("max_recoveries", max_recoveries, "recoveries per navigation at most");
    v("turn_rate_radps", turn_rate_radps, "turn rate of the turn in place [rad/s]");
    v("max_turn_rad", max_turn_rad, "a turn in place turns at most this far [rad]");
    v("min_turn_rad", min_turn_rad, "a turn in place shorter than this is not tried [rad]");
    v("reverse_speed_mps", reverse_speed_mps, "speed of the reversing manoeuvres [m/s]");
    v("reverse_turn_radps", reverse_turn_radps, "turn rate of the reversing arcs [rad/s]");
    v("reverse_distance_m", reverse_distance_m, "a reverse drives at most this far [m]");
    v("min_reverse_m", min_reverse_m, "a reverse shorter than this is not tried [m]");
    v("into_unobserved", into_unobserved,
      "a manoeuvre may drive onto ground the map has not observed (false: unknown cells count "
      "as obstacles)");
  }
};

/// One manoeuvre: a constant command held for duration_s (zero: none feasible).
struct RecoveryMotion {
  Twist2D command;
  double duration_s = 0.0;
  bool feasible() const { return duration_s > 0.0; }
};

/// Signed distance from p_robot to the axis-aligned rectangle |x| <= half_length_m,
/// |y| <= half_width_m (negative inside) [m].
double rectangleSignedDistance(const Eigen::Vector2d& p_robot, double half_length_m,
                               double half_width_m);

/// Longest time up to max_duration_s for which the command (v, w), integrated from the robot
/// frame's origin, keeps every obstacle point (robot frame) outside the rectangle, or no deeper
/// inside it than it starts (a point already within the shape may be left, not entered further)
/// [s]. Checked every step_s.
double feasibleDuration(const std::vector<Eigen::Vector2d>& points_robot, double half_length_m,
                        double half_width_m, const Twist2D& command, double max_duration_s,
                        double step_s = 0.05);

/// The manoeuvre for a robot stalled among points_robot (its shape the rectangle), with the
/// route heading heading_error_rad away (robot frame, counter-clockwise positive): a turn in
/// place towards it when at least min_turn_rad of it is feasible, else the longest of the
/// reversing arcs (towards the route, straight, away) when at least min_reverse_m, else none.
/// unobserved_robot: centres of the map's unknown cells near the robot (robot frame); unless
/// params.into_unobserved they are obstacle points too, except those inside the shape at the
/// start (the robot stands on that ground).
RecoveryMotion planRecovery(const std::vector<Eigen::Vector2d>& points_robot,
                            const std::vector<Eigen::Vector2d>& unobserved_robot,
                            double half_length_m, double half_width_m, double heading_error_rad,
                            const RecoveryParams& params);
/// The same with no unknown ground around the robot.
RecoveryMotion planRecovery(const std::vector<Eigen::Vector2d>& points_robot, double half_length_m,
                            double half_width_m, double heading_error_rad,
                            const RecoveryParams& params);

/// How far from the robot's centre an unknown cell can matter to a manoeuvre: the shape's
/// half-diagonal plus the reverse distance plus cell_size_m [m].
double recoveryReach(double half_length_m, double half_width_m, const RecoveryParams& params,
                     double cell_size_m);

}  // namespace upd::nav
