// The robot-base interface for integrators: what the navigator needs from a wheeled base, and
// the simulated differential-drive base that UPD-Nav ships.
//
// To drive a real robot with `upd live --navigate`, implement RobotBase over the robot's driver
// (and its localization) and pass it to NavigationLoop (navigation_loop.h): the navigator calls
// readState() and sendVelocity() once per control step, stop() when it ends or fails. Nothing
// else of the project needs to change. docs/NAVIGATION.md walks through an implementation.
//
// Frames: the world (map) frame is z up; the robot frame is x forward, y left, z up, with its
// origin at the centre of the footprint on the ground. pose_world_robot maps robot-frame
// coordinates to world-frame coordinates.
#pragma once

#include <memory>
#include <string>

namespace upd::nav {

/// A planar pose: the robot frame in the world frame.
struct Pose2D {
  double x_m = 0.0;
  double y_m = 0.0;
  double yaw_rad = 0.0;  ///< heading of the robot's x axis from the world's x axis [rad]
};

/// The velocity of a differential-drive base, in its own frame.
struct Twist2D {
  double v_mps = 0.0;    ///< forward speed [m/s]
  double w_radps = 0.0;  ///< turn rate, counter-clockwise positive [rad/s]
};

/// What a base reports each control step.
struct BaseState {
  Pose2D pose_world_robot;  ///< from localization (or odometry when there is none)
  Pose2D pose_odom_robot;   ///< raw odometry; may drift, locally smooth
  Twist2D velocity;         ///< measured velocity in the robot frame
};

/// A wheeled base the navigator drives. Implementations must be cheap to call (cache values
/// that take longer than ~10 ms to read). Every method returns false on a failure to talk to the
/// base; the navigator then stops the robot and ends with an error.
class RobotBase {
 public:
  virtual ~RobotBase() = default;

  /// The latest pose and velocity.
  virtual bool readState(BaseState& state) = 0;
  /// Commands v and w until the next command (the base should stop by itself if no command
  /// arrives for a while: a watchdog).
  virtual bool sendVelocity(const Twist2D& command) = 0;
  /// Stops the robot; emergency = as fast as the base can.
  virtual bool stop(bool emergency) = 0;
  /// Seconds on the clock the navigation runs on: simulated time for a simulator, a monotonic
  /// wall clock for a real robot. Only differences are used.
  virtual double timeS() const = 0;
  /// Why the last call failed, for the one-line error a run ends with ("" when unknown).
  virtual std::string lastError() const { return {}; }
};

/// Dynamics of the simulated base. Loaded from [SimulatedBaseParams].
struct SimulatedBaseParams {
  double velocity_lag_s = 0.1;   ///< first-order lag of the wheels' response to commands [s]
  double command_delay_s = 0.0;  ///< dead time before a command takes effect [s]

  void validate() const;
  template <class V>
  void visit(V& v) {
    v("velocity_lag_s", velocity_lag_s, "first-order lag of the velocity response [s] (>= 0)");
    v("command_delay_s", command_delay_s, "dead time before a command acts [s] (>= 0)");
  }
};

/// A kinematic differential-drive base (MRPT's CVehicleSimul_DiffDriven): exact pose, no
/// odometry drift, time advanced by advance(). It is the base `upd navigate` drives and the one
/// `upd live` uses when no real base is plugged in.
class SimulatedDiffDrive : public RobotBase {
 public:
  explicit SimulatedDiffDrive(const Pose2D& start, const SimulatedBaseParams& params = {});
  ~SimulatedDiffDrive() override;
  SimulatedDiffDrive(const SimulatedDiffDrive&) = delete;
  SimulatedDiffDrive& operator=(const SimulatedDiffDrive&) = delete;

  bool readState(BaseState& state) override;
  bool sendVelocity(const Twist2D& command) override;
  bool stop(bool emergency) override;
  double timeS() const override;

  /// Integrates the motion over dt_s (> 0) seconds.
  void advance(double dt_s);
  /// The exact pose (what readState reports).
  Pose2D pose() const;
  /// The last commanded velocity.
  Twist2D lastCommand() const { return last_command_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  Twist2D last_command_;
};

}  // namespace upd::nav
