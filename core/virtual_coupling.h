#pragma once
// Virtual coupling (DESIGN.md §3; Colgate, Stanley & Brown 1995; Otaduy & Lin 2005): a 6-DOF
// spring–damper between the device pose (frame D, what the user holds) and the simulated tool
// (frame T). With the orientation error e = q_WD q_WT⁻¹ (world frame) and θ(e) its rotation
// vector,
//   F = k_c (x_d − x) + b_c (v_d − v),        T = k_θ θ(q_WD q_WT⁻¹) + b_θ (ω_d − ω),
// the force and torque on the tool (world, about its COM). The device receives the reaction
// −F, −T (its handle is pulled back toward the tool). The torque does not include the moment of
// F about the COM (the device point is taken to coincide with the tool COM).
//
// Jacobians with respect to the tool state, used by the implicit integrator (tool_integrator.h):
//   ∂F/∂x = −k_c I,  ∂F/∂v = −b_c I,  ∂T/∂ω = −b_θ I,
//   ∂T/∂θ = −k_θ J_r⁻¹(θ),  for a world-frame rotation δ of the tool, q_WT ← exp(δ) q_WT:
//   θ(q_d (exp(δ) q)⁻¹) = θ(e exp(−δ)) = θ − J_r⁻¹(θ) δ + O(δ²)
// (right Jacobian of SO(3): exp(θ + Δθ) = exp(θ) exp(J_r(θ) Δθ); Chirikjian 2011, Solà et al.
// 2018 "A micro Lie theory for state estimation in robotics").

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/rigid_tool.h"

namespace hapsim {

struct CouplingParams {
  double k_lin_N_m = 0.0;        // k_c
  double b_lin_N_s_m = 0.0;      // b_c
  double k_ang_N_m_rad = 0.0;    // k_θ
  double b_ang_N_m_s_rad = 0.0;  // b_θ
};

// Pose and velocity of the device handle in the world (after the device-to-world map at the
// edge: workspace scaling and offset are applied by the device backend).
struct DeviceState {
  Eigen::Vector3d x_W_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W_m_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d w_W_rad_s = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WD = Eigen::Quaterniond::Identity();
  // Bit i set while button i is pressed (bit 0 the primary button: it grabs, paper 003).
  int buttons = 0;
};

// Wrench on the tool (world) and its Jacobians with respect to the tool's x, v, rotation δ
// (world, q ← exp(δ) q) and ω.
struct CouplingWrench {
  Eigen::Vector3d F_W_N = Eigen::Vector3d::Zero();
  Eigen::Vector3d T_W_N_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d dF_dx = Eigen::Matrix3d::Zero();      // N/m
  Eigen::Matrix3d dF_dv = Eigen::Matrix3d::Zero();      // N s/m
  Eigen::Matrix3d dT_dtheta = Eigen::Matrix3d::Zero();  // N m/rad
  Eigen::Matrix3d dT_domega = Eigen::Matrix3d::Zero();  // N m s/rad
};

// w_tool_W_rad_s is the tool's ω = M⁻¹ L (CalcAngularVelocity), passed in so it is computed once.
CouplingWrench CalcCouplingWrench(const CouplingParams& params, const DeviceState& device,
                                  const ToolState& tool, const Eigen::Vector3d& w_tool_W_rad_s);

// Rotation vector θ = log(q) ∈ the ball |θ| ≤ π: q is first replaced by −q if w < 0 (the same
// rotation; this picks the shortest one), then θ = 2 atan2(|u|, w) u/|u| for q = (w, u), with
// the series 2/w (1 − |u|²/(3w²)) near |u| = 0. atan2 keeps it accurate up to |θ| = π.
Eigen::Vector3d CalcRotationVector(const Eigen::Quaterniond& q);

// J_r⁻¹(θ) = I + ½[θ]× + (1/|θ|² − (1 + cos|θ|)/(2|θ| sin|θ|)) [θ]×², the last coefficient
// written as 1/|θ|² − cot(|θ|/2)/(2|θ|) (finite up to π) and as 1/12 + |θ|²/720 + |θ|⁴/30240
// near 0.
Eigen::Matrix3d CalcInverseRightJacobianSO3(const Eigen::Vector3d& theta_rad);

}  // namespace hapsim
