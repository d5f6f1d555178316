#pragma once
// The linear contact model of Otaduy & Gross (DESIGN.md §4, the paper's eq. 13): the contact
// force and torque on the tool as an affine function of the discrete-time force and torque
//   F̂ = F̃ + A_v v/Δt,   T̂ = T̃ + A_L L/Δt
// (the tool's own momentum plus the user's motion through the coupling), with the constraint
// set, W and the body's velocities frozen at the visual frame:
//
//   F_c = F_c0 + (∂F_c/∂F̂) F̂ + (∂F_c/∂T̂) T̂          T_c = T_c0 + (∂T_c/∂F̂) F̂ + (∂T_c/∂T̂) T̂
//   F_c0 = J_vᵀ W⁻¹ (b − J_u u̇)/Δt                    T_c0 = J_ωᵀ W⁻¹ (b − J_u u̇)/Δt
//   ∂F_c/∂F̂ = −J_vᵀ W⁻¹ J_v A_v⁻¹                     ∂T_c/∂F̂ = −J_ωᵀ W⁻¹ J_v A_v⁻¹
//   ∂F_c/∂T̂ = −J_vᵀ W⁻¹ J_ω M⁻¹ A_L⁻¹                 ∂T_c/∂T̂ = −J_ωᵀ W⁻¹ J_ω M⁻¹ A_L⁻¹
//
// It follows from the equality solve Δt W λ = b − c_free with c_free = J_v A_v⁻¹ Δt F̂ +
// J_ω M⁻¹ A_L⁻¹ Δt T̂ + J_u u̇ and F_c = J_vᵀλ, T_c = J_ωᵀλ, so it reproduces that solve exactly
// for any F̂, T̂ as long as the contacts stay active. W is the caller's: under the equality law
// with that law's compliance on its diagonal, as the frame's solve has it (contact_solver.h).
// Building it costs six solves with W (plus one for the offset); evaluating it four 3×3 products.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "contact/contact_jacobian.h"
#include "core/rigid_tool.h"
#include "core/tool_integrator.h"

namespace hapsim::contact {

struct LinearContactModel {
  Eigen::Vector3d F_c0_N = Eigen::Vector3d::Zero();    // force offset, world
  Eigen::Vector3d T_c0_N_m = Eigen::Vector3d::Zero();  // torque offset about the tool COM, world
  Eigen::Matrix3d dFc_dF = Eigen::Matrix3d::Zero();    // ∂F_c/∂F̂, dimensionless
  Eigen::Matrix3d dFc_dT = Eigen::Matrix3d::Zero();    // ∂F_c/∂T̂, 1/m
  Eigen::Matrix3d dTc_dF = Eigen::Matrix3d::Zero();    // ∂T_c/∂F̂, m
  Eigen::Matrix3d dTc_dT = Eigen::Matrix3d::Zero();    // ∂T_c/∂T̂, dimensionless
  int num_contacts = 0;
};

// Builds the model. `tool` holds A_v, A_L, M⁻¹ and Δt of the step the model will be evaluated
// at (the haptic step); W must have been built with those same tool matrices. body_rhs =
// b − J_u u̇ (one entry per constraint row). A singular W (redundant contacts) gets the
// minimum-norm solution.
LinearContactModel MakeLinearContactModel(const ContactJacobian& J, const Eigen::MatrixXd& W,
                                          const ToolStepSystem& tool,
                                          const Eigen::VectorXd& body_rhs);

// F_c, T_c for the given F̂, T̂. Allocation-free (1 kHz loop).
void EvaluateLinearContactModel(const LinearContactModel& model, const Eigen::Vector3d& F_hat_N,
                                const Eigen::Vector3d& T_hat_N_m, Eigen::Vector3d* F_c_N,
                                Eigen::Vector3d* T_c_N_m);

// F̂ = F̃ + A_v v/Δt and T̂ = T̃ + A_L L/Δt for the tool at `state`. Allocation-free.
void CalcDiscreteTimeWrench(const ToolStepSystem& tool, const ToolState& state,
                            Eigen::Vector3d* F_hat_N, Eigen::Vector3d* T_hat_N_m);

// Tool part of the Delassus matrix, J_v A_v⁻¹ J_vᵀ + J_ω M⁻¹ A_L⁻¹ J_ωᵀ (rows x rows).
Eigen::MatrixXd CalcToolDelassus(const ContactJacobian& J, const ToolStepSystem& tool);
// W += that part, in place (W: rows x rows), with no rows x rows temporary. Throws
// std::invalid_argument if W is not rows x rows.
void AddToolDelassus(const ContactJacobian& J, const ToolStepSystem& tool, Eigen::MatrixXd* W);

// The same rank-6 part [J_v J_ω] S [J_v J_ω]ᵀ, S = blockdiag(A_v⁻¹, M⁻¹A_L⁻¹), a column or the
// diagonal at a time (6 products an entry), for a W formed by the columns a solve reads
// (FrameCompliance). A rigid body's rows (a dynamic object's J and system) give its part alike.
class ToolDelassusColumns {
 public:
  ToolDelassusColumns(const ContactJacobian& J, const ToolStepSystem& tool);
  Eigen::Index rows() const { return J_tool_.rows(); }
  // W(:, col) += the part's column col (W: rows x rows), but at the rows marked in `skip` (may
  // be null: none).
  void AddColumn(Eigen::Index col, Eigen::MatrixXd* W,
                 const std::vector<std::uint8_t>* skip = nullptr) const;
  // diagonal += the part's diagonal.
  void AddDiagonal(Eigen::VectorXd* diagonal) const;
  // W += the whole part, one product.
  void AddAll(Eigen::MatrixXd* W) const;

 private:
  Eigen::Matrix<double, Eigen::Dynamic, 6> J_tool_;    // [J_v J_ω]
  Eigen::Matrix<double, Eigen::Dynamic, 6> J_tool_S_;  // [J_v J_ω] Sᵀ
};

}  // namespace hapsim::contact
