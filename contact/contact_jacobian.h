#pragma once
// Velocity-level contact constraints between the tool and the body (DESIGN.md §4).
//
// For contact i with normal n_i (out of the tool) at tool point p_i, lever r_i = p_i − x (x the
// tool's centre of mass), the separating normal velocity is
//   c_i = J_v,i v + J_ω,i ω + J_u,i u̇,   J_v,i = −n_iᵀ,  J_ω,i = −(r_i × n_i)ᵀ,  J_u,i = Σ_k w_k
//   n_iᵀ
// (the last at the dofs of the body nodes k carrying the contact point). A multiplier λ_i ≥ 0
// pushes the bodies apart: the force on the tool is F_c = J_vᵀλ, the torque T_c = J_ωᵀλ, and the
// force on the body J_uᵀλ. With friction each contact has two more rows, along tangents t1, t2
// (n, t1, t2 right-handed), built the same way with t in place of n. A contact with on_tool =
// false (a body node on a rigid object) has J_v = J_ω = 0; a contact with no body nodes (the tool
// on a rigid object) has J_u = 0.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "contact/contact.h"

namespace hapsim::contact {

struct ContactJacobian {
  int rows_per_contact = 1;         // 1: normal only; 3: normal, t1, t2
  Eigen::MatrixX3d J_v;             // (rows x 3)
  Eigen::MatrixX3d J_w;             // (rows x 3)
  Eigen::SparseMatrix<double> J_u;  // (rows x 3N); columns of fixed dofs are left empty
  int num_rows() const { return static_cast<int>(J_v.rows()); }
};

// Builds the Jacobian rows of `contacts` for a tool whose centre of mass is at x_tool_W_m.
ContactJacobian CalcContactJacobian(const std::vector<Contact>& contacts,
                                    const Eigen::Vector3d& x_tool_W_m, int rows_per_contact,
                                    int num_dofs, const std::vector<std::uint8_t>& dof_is_fixed);

// The rows `rows` of J (row indices, each at most once, in the order given, whole contacts:
// rows_per_contact consecutive rows of one contact in their order): J_v and J_ω gathered, J_u's
// entries renumbered with each column's rows sorted again. The Jacobian CalcContactJacobian gives
// for those contacts at the same tool position, without copying or recomputing them. Throws
// std::invalid_argument for a row outside J or given twice, or a contact's rows split.
ContactJacobian SelectRows(const ContactJacobian& J, const std::vector<int>& rows);

// Two unit tangents completing n to a right-handed orthonormal frame (n, t1, t2), chosen
// continuously away from n = ±x.
void CalcTangents(const Eigen::Vector3d& n, Eigen::Vector3d* t1, Eigen::Vector3d* t2);

}  // namespace hapsim::contact
