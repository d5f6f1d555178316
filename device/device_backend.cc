#include "device/device_backend.h"

#include <stdexcept>

namespace hapsim::device {

DeviceState ScriptedDevice::Read(double t_s, double* age_s, long* sequence) {
  *age_s = 0.0;
  *sequence = count_++;
  return script_.Sample(t_s);
}

SimulatedHand::SimulatedHand(ScriptedTrajectory script, const HandParams& params, double dt_s)
    : script_(std::move(script)), params_(params), dt_s_(dt_s) {
  if (!(params.mass_kg > 0.0) || !(params.k_N_m >= 0.0) || !(params.b_N_s_m >= 0.0) ||
      !(dt_s > 0.0))
    throw std::invalid_argument("SimulatedHand: mass and dt must be > 0, k and b >= 0");
}

DeviceState SimulatedHand::Read(double t_s, double* age_s, long* sequence) {
  target_ = script_.Sample(t_s);
  if (!started_) {  // the hand starts on its target, at rest relative to it
    x_W_m_ = target_.x_W_m;
    v_W_m_s_ = target_.v_W_m_s;
    started_ = true;
  }
  DeviceState state = target_;
  state.x_W_m = x_W_m_;
  state.v_W_m_s = v_W_m_s_;
  *age_s = 0.0;
  *sequence = count_++;
  return state;
}

void SimulatedHand::Write(const Eigen::Vector3d& force_W_N, const Eigen::Vector3d&) {
  if (!started_ || !force_W_N.allFinite()) return;
  const Eigen::Vector3d arm_N = params_.k_N_m * (target_.x_W_m - x_W_m_) +
                                params_.b_N_s_m * (target_.v_W_m_s - v_W_m_s_);
  v_W_m_s_ += dt_s_ / params_.mass_kg * (arm_N + force_W_N);  // velocity first: symplectic
  x_W_m_ += dt_s_ * v_W_m_s_;
}

}  // namespace hapsim::device
