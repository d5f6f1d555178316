#include "core/tool_integrator.h"

#include <Eigen/LU>

namespace hapsim {

ToolStepSystem CalcToolStepSystem(const ToolModel& model, const ToolState& state,
                                  const CouplingWrench& coupling,
                                  const Eigen::Vector3d& gravity_m_s2, double dt_s,
                                  const Eigen::Vector3d& external_force_W_N,
                                  const Eigen::Vector3d& external_torque_W_N_m) {
  ToolStepSystem system;
  system.dt_s = dt_s;
  system.M_inv_W = CalcWorldInverseInertia(model, state.q_WT);
  const Eigen::Vector3d w_W_rad_s = system.M_inv_W * state.L_W_kg_m2_s;
  const double dt2 = dt_s * dt_s;
  // Translation: A_v = m I − Δt ∂F/∂v − Δt² ∂F/∂x,  F̃ = F + Δt (∂F/∂x) v.
  system.A_v =
      model.mass_kg * Eigen::Matrix3d::Identity() - dt_s * coupling.dF_dv - dt2 * coupling.dF_dx;
  const Eigen::Vector3d F_N = model.mass_kg * gravity_m_s2 + coupling.F_W_N + external_force_W_N;
  system.F_tilde_N = F_N + dt_s * coupling.dF_dx * state.v_W_m_s;
  // Rotation: A_L = I − Δt (∂T/∂ω) M⁻¹ − Δt² (∂T/∂θ) M⁻¹,  T̃ = T + Δt (∂T/∂θ) ω.
  system.A_L = Eigen::Matrix3d::Identity() -
               (dt_s * coupling.dT_domega + dt2 * coupling.dT_dtheta) * system.M_inv_W;
  const Eigen::Vector3d T_N_m = coupling.T_W_N_m + external_torque_W_N_m;
  system.T_tilde_N_m = T_N_m + dt_s * coupling.dT_dtheta * w_W_rad_s;
  return system;
}

void CalcFreeVelocityChange(const ToolStepSystem& system, Eigen::Vector3d* dv_W_m_s,
                            Eigen::Vector3d* dL_W_kg_m2_s) {
  // 3×3 LU with partial pivoting on fixed-size matrices: on the stack. A_L is not symmetric
  // (J_r⁻¹ has a skew part and the product with M⁻¹), so no Cholesky.
  *dv_W_m_s = system.A_v.partialPivLu().solve(system.dt_s * system.F_tilde_N);
  *dL_W_kg_m2_s = system.A_L.partialPivLu().solve(system.dt_s * system.T_tilde_N_m);
}

void AdvanceTool(const ToolModel& model, double dt_s, const Eigen::Vector3d& dv_W_m_s,
                 const Eigen::Vector3d& dL_W_kg_m2_s, ToolState* state) {
  state->v_W_m_s += dv_W_m_s;
  state->L_W_kg_m2_s += dL_W_kg_m2_s;
  state->x_W_m += dt_s * state->v_W_m_s;
  const Eigen::Vector3d w_W_rad_s = CalcAngularVelocity(model, *state);
  state->q_WT = CalcQuaternionExp(dt_s * w_W_rad_s) * state->q_WT;
  state->q_WT.normalize();
}

}  // namespace hapsim
