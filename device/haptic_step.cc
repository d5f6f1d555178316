#include "device/haptic_step.h"

#include <Eigen/LU>

#include "core/tool_integrator.h"

namespace hapsim::device {

HapticStep::HapticStep(ToolModel tool, const CouplingParams& coupling,
                       const Eigen::Vector3d& gravity_m_s2, double dt_s,
                       const ToolState& initial_tool, int lcp_max_rows,
                       int lcp_friction_sweeps)
    : tool_(std::move(tool)),
      coupling_(coupling),
      gravity_m_s2_(gravity_m_s2),
      dt_s_(dt_s),
      tool_state_(initial_tool),
      lcp_(lcp_max_rows, lcp_friction_sweeps) {}

HapticOutput HapticStep::Step(const DeviceState& device) {
  const CouplingWrench wrench =
      CalcCouplingWrench(coupling_, device, tool_state_, CalcAngularVelocity(tool_, tool_state_));
  const ToolStepSystem system =
      CalcToolStepSystem(tool_, tool_state_, wrench, gravity_m_s2_, dt_s_);
  Eigen::Vector3d F_hat_N, T_hat_N_m;
  contact::CalcDiscreteTimeWrench(system, tool_state_, &F_hat_N, &T_hat_N_m);
  HapticOutput out;
  if (geometric_ != nullptr) {
    geometric_->Calc(system, tool_state_, &out.contact_force_W_N, &out.contact_torque_W_N_m);
  } else if (rows_ != nullptr) {
    out.lcp_fell_back = !solver_->Solve(*rows_, system, F_hat_N, T_hat_N_m, &out.contact_force_W_N,
                                        &out.contact_torque_W_N_m);
  }
  if (geometric_ == nullptr && (rows_ == nullptr || out.lcp_fell_back)) {
    contact::EvaluateLinearContactModel(model_, F_hat_N, T_hat_N_m, &out.contact_force_W_N,
                                        &out.contact_torque_W_N_m);
  }
  const Eigen::Vector3d dv =
      system.A_v.lu().solve(dt_s_ * (system.F_tilde_N + out.contact_force_W_N));
  const Eigen::Vector3d dL =
      system.A_L.lu().solve(dt_s_ * (system.T_tilde_N_m + out.contact_torque_W_N_m));
  AdvanceTool(tool_, dt_s_, dv, dL, &tool_state_);
  out.device_force_W_N = -wrench.F_W_N;
  out.device_torque_W_N_m = -wrench.T_W_N_m;
  return out;
}

bool HapticStep::PrepareContactRows(const contact::ContactRows& rows) {
  return lcp_.Prepare(rows,
                      CalcLinearisationSystem(tool_, coupling_, gravity_m_s2_, dt_s_, tool_state_));
}

ToolStepSystem CalcLinearisationSystem(const ToolModel& tool, const CouplingParams& coupling,
                                       const Eigen::Vector3d& gravity_m_s2, double dt_s,
                                       const ToolState& state) {
  // The coupling's Jacobians at zero coupling error: the device at the tool.
  const DeviceState at_tool = MakeDeviceAtTool(tool, state);
  const CouplingWrench wrench = CalcCouplingWrench(coupling, at_tool, state, at_tool.w_W_rad_s);
  return CalcToolStepSystem(tool, state, wrench, gravity_m_s2, dt_s);
}

DeviceState MakeDeviceAtTool(const ToolModel& tool, const ToolState& state) {
  DeviceState device;
  device.x_W_m = state.x_W_m;
  device.v_W_m_s = state.v_W_m_s;
  device.q_WD = state.q_WT;
  device.w_W_rad_s = CalcAngularVelocity(tool, state);
  return device;
}

DeviceState HapticStep::tool_as_target() const { return MakeDeviceAtTool(tool_, tool_state_); }

}  // namespace hapsim::device
