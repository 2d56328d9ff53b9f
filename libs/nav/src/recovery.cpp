#include "upd/nav/recovery.h"

#include "upd/core/params.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace upd::nav {

void RecoveryParams::validate() const {
  const char* s = "RecoveryParams";
  core::requireParam(std::isfinite(stall_time_s) && stall_time_s > 0, s, "stall_time_s",
                     stall_time_s, "must be > 0");
  core::requireParam(std::isfinite(stall_radius_m) && stall_radius_m > 0, s, "stall_radius_m",
                     stall_radius_m, "must be > 0");
  core::requireParam(max_recoveries >= 0, s, "max_recoveries", max_recoveries, "must be >= 0");
  core::requireParam(std::isfinite(turn_rate_radps) && turn_rate_radps > 0, s, "turn_rate_radps",
                     turn_rate_radps, "must be > 0");
  core::requireParam(std::isfinite(max_turn_rad) && max_turn_rad > 0, s, "max_turn_rad",
                     max_turn_rad, "must be > 0");
  core::requireParam(std::isfinite(min_turn_rad) && min_turn_rad >= 0 && min_turn_rad <= max_turn_rad,
                     s, "min_turn_rad", min_turn_rad, "must be in [0, max_turn_rad]");
  core::requireParam(std::isfinite(reverse_speed_mps) && reverse_speed_mps > 0, s,
                     "reverse_speed_mps", reverse_speed_mps, "must be > 0");
  core::requireParam(std::isfinite(reverse_turn_radps) && reverse_turn_radps >= 0, s,
                     "reverse_turn_radps", reverse_turn_radps, "must be >= 0");
  core::requireParam(std::isfinite(reverse_distance_m) && reverse_distance_m > 0, s,
                     "reverse_distance_m", reverse_distance_m, "must be > 0");
  core::requireParam(std::isfinite(min_reverse_m) && min_reverse_m >= 0 &&
                         min_reverse_m <= reverse_distance_m,
                     s, "min_reverse_m", min_reverse_m, "must be in [0, reverse_distance_m]");
}

double rectangleSignedDistance(const Eigen::Vector2d& p_robot, double half_length_m,
                               double half_width_m) {
  const double dx = std::abs(p_robot.x()) - half_length_m;
  const double dy = std::abs(p_robot.y()) - half_width_m;
  if (dx <= 0 && dy <= 0) return std::max(dx, dy);
  return std::hypot(std::max(dx, 0.0), std::max(dy, 0.0));
}

double feasibleDuration(const std::vector<Eigen::Vector2d>& points_robot, double half_length_m,
                        double half_width_m, const Twist2D& command, double max_duration_s,
                        double step_s) {
  // Only points the shape can reach during the motion matter.
  const double reach = std::hypot(half_length_m, half_width_m) +
                       std::abs(command.v_mps) * max_duration_s + step_s;
  std::vector<Eigen::Vector2d> near;
  std::vector<double> start_sd;
  for (const auto& p : points_robot) {
    if (!p.allFinite() || p.norm() > reach) continue;
    near.push_back(p);
    start_sd.push_back(rectangleSignedDistance(p, half_length_m, half_width_m));
  }
  const int n = static_cast<int>(std::ceil(max_duration_s / step_s));
  double ok_s = 0.0;
  for (int k = 1; k <= n; ++k) {
    const double t = std::min(k * step_s, max_duration_s);
    const double th = command.w_radps * t;
    double x, y;
    if (std::abs(command.w_radps) < 1e-9) {
      x = command.v_mps * t;
      y = 0.0;
    } else {
      x = command.v_mps / command.w_radps * std::sin(th);
      y = command.v_mps / command.w_radps * (1.0 - std::cos(th));
    }
    const double c = std::cos(th), s = std::sin(th);
    for (std::size_t i = 0; i < near.size(); ++i) {
      const double dx = near[i].x() - x, dy = near[i].y() - y;
      const Eigen::Vector2d q(c * dx + s * dy, -s * dx + c * dy);
      const double sd = rectangleSignedDistance(q, half_length_m, half_width_m);
      // Outside the shape stays outside; inside may not go deeper (1 mm of slack).
      if (sd < std::min(0.0, start_sd[i]) - 1e-3) return ok_s;
    }
    ok_s = t;
  }
  return ok_s;
}

RecoveryMotion planRecovery(const std::vector<Eigen::Vector2d>& points_robot, double half_length_m,
                            double half_width_m, double heading_error_rad,
                            const RecoveryParams& params) {
  return planRecovery(points_robot, {}, half_length_m, half_width_m, heading_error_rad, params);
}

double recoveryReach(double half_length_m, double half_width_m, const RecoveryParams& params,
                     double cell_size_m) {
  return std::hypot(half_length_m, half_width_m) + params.reverse_distance_m + cell_size_m;
}

RecoveryMotion planRecovery(const std::vector<Eigen::Vector2d>& obstacles_robot,
                            const std::vector<Eigen::Vector2d>& unobserved_robot,
                            double half_length_m, double half_width_m, double heading_error_rad,
                            const RecoveryParams& params) {
  std::vector<Eigen::Vector2d> points_robot = obstacles_robot;
  if (!params.into_unobserved) {
    for (const Eigen::Vector2d& p : unobserved_robot) {
      if (rectangleSignedDistance(p, half_length_m, half_width_m) > 0.0) points_robot.push_back(p);
    }
  }
  const double turn_sign = heading_error_rad >= 0 ? 1.0 : -1.0;
  const double wanted_turn = std::min(std::abs(heading_error_rad), params.max_turn_rad);
  if (wanted_turn >= params.min_turn_rad) {
    RecoveryMotion turn;
    turn.command = {0.0, turn_sign * params.turn_rate_radps};
    const double t = feasibleDuration(points_robot, half_length_m, half_width_m, turn.command,
                                      wanted_turn / params.turn_rate_radps);
    if (t * params.turn_rate_radps >= params.min_turn_rad) {
      turn.duration_s = t;
      return turn;
    }
  }
  // Reversing: an arc that swings the front towards the route first, then straight, then away.
  const double max_t = params.reverse_distance_m / params.reverse_speed_mps;
  const double min_t = params.min_reverse_m / params.reverse_speed_mps;
  RecoveryMotion best;
  for (const double w : {turn_sign * params.reverse_turn_radps, 0.0,
                         -turn_sign * params.reverse_turn_radps}) {
    const Twist2D cmd{-params.reverse_speed_mps, w};
    const double t = feasibleDuration(points_robot, half_length_m, half_width_m, cmd, max_t);
    if (t >= max_t - 1e-9) return {cmd, t};
    if (t >= min_t && t > best.duration_s) best = {cmd, t};
  }
  return best;
}

}  // namespace upd::nav
