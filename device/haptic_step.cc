#include "device/haptic_step.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>

#include "core/tool_integrator.h"

namespace hapsim::device {

HapticStep::HapticStep(ToolModel tool, const CouplingParams& coupling,
                       const Eigen::Vector3d& gravity_m_s2, double dt_s,
                       const ToolState& initial_tool, int lcp_max_rows, int lcp_friction_sweeps,
                       bool hold_frame_contacts)
    : tool_(std::move(tool)),
      coupling_(coupling),
      gravity_m_s2_(gravity_m_s2),
      dt_s_(dt_s),
      tool_state_(initial_tool),
      lcp_(lcp_max_rows, lcp_friction_sweeps, hold_frame_contacts, kLcpSolvesPerStep),
      targets_(hold_frame_contacts ? std::max(lcp_max_rows, 0) : 0) {}

void HapticStep::SetContactRows(const contact::ContactRows* rows,
                                contact::HapticLcpSolver* prepared, const ToolState* linearised) {
  rows_ = rows;
  solver_ = prepared != nullptr ? prepared : &lcp_;
  rows_linearised_at_ = linearised != nullptr ? *linearised : tool_state_;
  steps_on_rows_ = 0;
}

// The hybrid mode, normal rows that carry their gaps, within the step's capacity.
bool HapticStep::TracksFreeRows() const {
  const Eigen::Index n = rows_->num_rows();
  return solver_->hold_frame_contacts() && rows_->rows_per_contact == 1 &&
         rows_->gap_m.size() == n && rows_->gap_target_m_s.size() == n &&
         rows_->surface_velocity_m_s.size() == n && rows_->lambda_frame_N.size() == n &&
         n <= targets_.size();
}

// The frame's free rows (not active at the frame) follow the haptic tool between frames. A row's
// gap now, to first order in the tool's motion since the rows' linearisation (Δx, and θ the
// rotation vector of q q₀⁻¹) and the surface's frozen velocity over the time τ since they came,
//   φ_i(t) = φ_i + J_v,i Δx + J_ω,i θ + surface_velocity_i τ        (dφ_i/dt),
// gives the gap target that lets this step close at most that gap, −max(φ_i(t), 0)/Δt, which
// takes the place of the frame's (gap_target_i = −φ_i/Δt_visual) in the row's body_rhs: the
// speculative contact of the 1 kHz reference, which engages a row when the tool reaches it. The
// frame's own target would engage it as soon as the approach could close the gap within a visual
// frame: early, a push on a resting tool and a drag on a sliding one (0.035 N RMS at rest on
// block_press). A row the tool has passed holds (target 0) until the next frame pushes it out.
// The surface velocity is the body's motion after the frame, not the contact-free velocity of
// body_rhs: that one assumes the frame's contact force gone, and integrated over a frame it moved
// the liver's surface millimetres into a resting tool. The held rows keep the frame's target, as
// the linear contact model does (the solver holds the same rows, λ_frame > 0, or solves one it
// has released unilaterally with that target), and so do a grasp's rows (bilateral).
void HapticStep::CalcFreeRowTargets() {
  const contact::ContactRows& rows = *rows_;
  const Eigen::Vector3d dx_W_m = tool_state_.x_W_m - rows_linearised_at_.x_W_m;
  const Eigen::AngleAxisd turn(tool_state_.q_WT * rows_linearised_at_.q_WT.conjugate());
  const Eigen::Vector3d theta_W_rad = turn.angle() * turn.axis();
  const double tau_s = steps_on_rows_ * dt_s_;
  for (Eigen::Index i = 0; i < rows.num_rows(); ++i) {
    if (rows.lambda_frame_N[i] > 0.0 || i < rows.num_bilateral_rows) {
      targets_[i] = rows.body_rhs[i];
      continue;
    }
    const double gap_m = rows.gap_m[i] + rows.J_v.row(i).dot(dx_W_m) +
                         rows.J_w.row(i).dot(theta_W_rad) + rows.surface_velocity_m_s[i] * tau_s;
    targets_[i] = rows.body_rhs[i] - rows.gap_target_m_s[i] - std::max(gap_m, 0.0) / dt_s_;
  }
}

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
    const bool track = TracksFreeRows();
    if (track) CalcFreeRowTargets();
    out.lcp_fell_back = !solver_->Solve(*rows_, system, F_hat_N, T_hat_N_m, &out.contact_force_W_N,
                                        &out.contact_torque_W_N_m, track ? &targets_ : nullptr);
    ++steps_on_rows_;
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
