#pragma once
// One step of the rigid tool: linearised backward Euler (DESIGN.md §3; Otaduy & Gross 2007,
// following Baraff & Witkin 1998). The forces are expanded to first order about the current
// state and evaluated at the end of the step (x + Δt v⁺, v⁺, θ + Δt ω⁺, ω⁺ = M⁻¹ L⁺):
//
//   A_v Δv = Δt F̃ (+ Δt J_vᵀλ),   A_v = m I − Δt ∂F/∂v − Δt² ∂F/∂x,
//                                 F̃  = F + Δt (∂F/∂x) v
//   A_L ΔL = Δt T̃ (+ Δt J_ωᵀλ),   A_L = I − Δt (∂T/∂ω) M⁻¹ − Δt² (∂T/∂θ) M⁻¹,
//                                 T̃  = T + Δt (∂T/∂θ) ω
//
// with F = m g + coupling (+ any external force), T = coupling torque, θ a world-frame rotation
// of the tool (q ← exp(δ) q) and M⁻¹ = R I_b⁻¹ Rᵀ frozen at the start of the step. The contact
// impulses λ (the bracketed terms) are added by the contact response (contact/); here the
// collision-free ("free") changes are computed, then applied with AdvanceTool.
//
// Why implicit: transparency wants the simulated tool as light as the real handle feels (a few
// grams, tiny rotational inertia) and the coupling as stiff as the device can render. An
// explicit (symplectic Euler) update of the mass–spring m, k is stable only if
// Δt < 2/ω_n = 2√(m/k), i.e. k < 4m/Δt² (k_θ < 4 I_min/Δt² for rotation, where I_min of a slim
// tool about its own axis is minute): at 1 kHz a 10 g tool caps k at 40 kN/m, and a pen-like
// tool's roll inertia (~1e-7 kg m²) caps k_θ near 0.4 N m/rad. Backward Euler is unconditionally
// stable for the (linear) spring–damper: the eigenvalues of its step map are 1/(1 − Δt λ) with
// Re λ ≤ 0, so the coupling energy never grows whatever m, I, k and Δt; the cost is numerical
// damping of the coupling's (far above haptic bandwidth) oscillation, not instability. So the
// mass and stiffness can be chosen for transparency, not for the integrator.
//
// The per-step functions use fixed-size types only and allocate nothing.

#include <Eigen/Core>

#include "core/rigid_tool.h"
#include "core/virtual_coupling.h"

namespace hapsim {

// The two 3×3 systems of one step, for the free update and for the contact response (the
// Delassus matrix uses A_v⁻¹ and M⁻¹ A_L⁻¹).
struct ToolStepSystem {
  double dt_s = 0.0;
  Eigen::Matrix3d A_v = Eigen::Matrix3d::Identity();      // kg
  Eigen::Matrix3d A_L = Eigen::Matrix3d::Identity();      // dimensionless
  Eigen::Matrix3d M_inv_W = Eigen::Matrix3d::Identity();  // world inverse inertia, 1/(kg m²)
  Eigen::Vector3d F_tilde_N = Eigen::Vector3d::Zero();    // F̃, world
  Eigen::Vector3d T_tilde_N_m = Eigen::Vector3d::Zero();  // T̃, world
};

// Builds A_v, A_L, F̃, T̃ from the coupling wrench (CalcCouplingWrench at this state), gravity
// and any further external force/torque on the tool (world; constant over the step).
ToolStepSystem CalcToolStepSystem(
    const ToolModel& model, const ToolState& state, const CouplingWrench& coupling,
    const Eigen::Vector3d& gravity_m_s2, double dt_s,
    const Eigen::Vector3d& external_force_W_N = Eigen::Vector3d::Zero(),
    const Eigen::Vector3d& external_torque_W_N_m = Eigen::Vector3d::Zero());

// Free (collision-free) momentum changes: Δv = A_v⁻¹ Δt F̃ (m/s), ΔL = A_L⁻¹ Δt T̃ (kg m²/s).
void CalcFreeVelocityChange(const ToolStepSystem& system, Eigen::Vector3d* dv_W_m_s,
                            Eigen::Vector3d* dL_W_kg_m2_s);

// Applies the changes and advances the pose:
//   v ← v + Δv,  L ← L + ΔL,  x ← x + Δt v,  ω = M⁻¹(q) L,  q ← exp(Δt ω) ⊗ q (normalised).
// M⁻¹ is taken at the start-of-step q, as in A_L.
void AdvanceTool(const ToolModel& model, double dt_s, const Eigen::Vector3d& dv_W_m_s,
                 const Eigen::Vector3d& dL_W_kg_m2_s, ToolState* state);

}  // namespace hapsim
