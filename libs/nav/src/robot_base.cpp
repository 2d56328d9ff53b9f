#include "upd/nav/robot_base.h"

#include "upd/core/params.h"

#include <mrpt/kinematics/CVehicleSimul_DiffDriven.h>
#include <mrpt/kinematics/CVehicleVelCmd_DiffDriven.h>

#include <cmath>
#include <stdexcept>

namespace upd::nav {

void SimulatedBaseParams::validate() const {
  core::requireParam(std::isfinite(velocity_lag_s) && velocity_lag_s >= 0, "SimulatedBaseParams",
               "velocity_lag_s", velocity_lag_s, "must be >= 0");
  core::requireParam(std::isfinite(command_delay_s) && command_delay_s >= 0, "SimulatedBaseParams",
               "command_delay_s", command_delay_s, "must be >= 0");
}

struct SimulatedDiffDrive::Impl {
  mrpt::kinematics::CVehicleSimul_DiffDriven sim;
};

SimulatedDiffDrive::SimulatedDiffDrive(const Pose2D& start, const SimulatedBaseParams& params)
    : impl_(std::make_unique<Impl>()) {
  params.validate();
  impl_->sim.setDelayModelParams(params.velocity_lag_s, params.command_delay_s);
  impl_->sim.setCurrentGTPose(mrpt::math::TPose2D(start.x_m, start.y_m, start.yaw_rad));
  impl_->sim.setCurrentOdometricPose(mrpt::math::TPose2D(start.x_m, start.y_m, start.yaw_rad));
}

SimulatedDiffDrive::~SimulatedDiffDrive() = default;

bool SimulatedDiffDrive::readState(BaseState& state) {
  const auto& p = impl_->sim.getCurrentGTPose();
  const auto& o = impl_->sim.getCurrentOdometricPose();
  const auto v = impl_->sim.getCurrentGTVelLocal();
  state.pose_world_robot = {p.x, p.y, p.phi};
  state.pose_odom_robot = {o.x, o.y, o.phi};
  state.velocity = {v.vx, v.omega};
  return true;
}

bool SimulatedDiffDrive::sendVelocity(const Twist2D& command) {
  if (!std::isfinite(command.v_mps) || !std::isfinite(command.w_radps)) return false;
  impl_->sim.movementCommand(command.v_mps, command.w_radps);
  last_command_ = command;
  return true;
}

bool SimulatedDiffDrive::stop(bool /*emergency*/) {
  impl_->sim.movementCommand(0.0, 0.0);
  last_command_ = {};
  return true;
}

double SimulatedDiffDrive::timeS() const { return impl_->sim.getTime(); }

void SimulatedDiffDrive::advance(double dt_s) {
  if (!(dt_s > 0) || !std::isfinite(dt_s)) {
    throw std::invalid_argument("SimulatedDiffDrive::advance: dt_s = " + std::to_string(dt_s) +
                                ": must be > 0");
  }
  impl_->sim.simulateOneTimeStep(dt_s);
}

Pose2D SimulatedDiffDrive::pose() const {
  const auto& p = impl_->sim.getCurrentGTPose();
  return {p.x, p.y, p.phi};
}

}  // namespace upd::nav
