#pragma once
// Synthetic problems for the haptic step's contact solves (haptic_lcp_test.cc,
// haptic_friction_test.cc), as in contact_response_test.cc: a body with a random dense SPD
// matrix A_u, a tool with a hand-set ToolStepSystem, contacts with random normals and points.

#include <Eigen/Dense>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "contact/contact.h"
#include "contact/contact_jacobian.h"
#include "contact/haptic_contact_rows.h"
#include "contact/linear_contact_model.h"
#include "core/tool_integrator.h"

namespace hapsim::contact {

inline constexpr double kDt_s = 1e-3;

struct LcpProblem {
  ContactJacobian J;  // full Jacobian (with J_u), for the linear model
  ContactRows rows;
  ToolStepSystem tool;
  Eigen::Vector3d F_hat_N = Eigen::Vector3d::Zero();
  Eigen::Vector3d T_hat_N_m = Eigen::Vector3d::Zero();
};

// A 50 g tool on a stiff coupling at the haptic step. The coupling's torque Jacobian has a
// non-symmetric part (a rotation error), so W is not symmetric. `variant` changes A_L, M⁻¹.
inline ToolStepSystem MakeTool(double variant) {
  ToolStepSystem tool;
  tool.dt_s = kDt_s;
  const double m_kg = 0.05, k_N_m = 2000.0, b_N_s_m = 2.0;
  tool.A_v = (m_kg + kDt_s * b_N_s_m + kDt_s * kDt_s * k_N_m) * Eigen::Matrix3d::Identity();
  tool.A_v(0, 1) = tool.A_v(1, 0) = 0.002 * variant;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.7 * variant, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Matrix3d inertia = Eigen::Vector3d(2e-5, 3e-5, 1e-5).asDiagonal();
  tool.M_inv_W = rotation * inertia.inverse() * rotation.transpose();
  Eigen::Matrix3d skew;
  skew << 0, -1, 0.5, 1, 0, -2, -0.5, 2, 0;
  const Eigen::Matrix3d C = (kDt_s * 0.01 + kDt_s * kDt_s * 1.0) * Eigen::Matrix3d::Identity() +
                            kDt_s * kDt_s * (0.3 + variant) * skew;
  tool.A_L = Eigen::Matrix3d::Identity() + C * tool.M_inv_W;
  return tool;
}

// n contacts on a body of n + 1 nodes (contact i between nodes i and i + 1), so that W_body =
// J_u A_u⁻¹ J_uᵀ has full rank; `body_scale` scales the body's compliance (small: a stiff body,
// W close to the rank-6 tool part). `press` shifts the targets: large makes every contact
// active, 0 gives a mix of pressing and separating contacts.
// With rows_per_contact 3 (friction rows: normal, t1, t2 per contact) n counts contacts, each
// tangential target is random (a body sliding under the tool) and every μ is `mu`.
inline LcpProblem MakeLcpProblem(int n, unsigned seed, double press = 0.0, double body_scale = 1.0,
                                 int rows_per_contact = 1, double mu = 0.0) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto random3 = [&] { return Eigen::Vector3d(unit(rng), unit(rng), unit(rng)); };
  LcpProblem p;
  p.tool = MakeTool(0.0);
  const int num_dofs = 3 * (n + 1);
  ToolState tool_state;
  tool_state.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.02);
  tool_state.v_W_m_s = 0.05 * random3();
  tool_state.L_W_kg_m2_s = 1e-6 * random3();
  std::vector<Contact> contacts;
  for (int i = 0; i < n; ++i) {
    Contact c;
    c.n_W = (random3() + Eigen::Vector3d(0, 0, -2.0)).normalized();  // tool pressing down
    c.p_tool_W_m = tool_state.x_W_m + 0.01 * random3();
    c.nodes = {i, i + 1, -1};
    const double w = 0.5 + 0.4 * unit(rng);
    c.weights = {w, 1.0 - w, 0.0};
    contacts.push_back(c);
  }
  p.J = CalcContactJacobian(contacts, tool_state.x_W_m, rows_per_contact, num_dofs,
                            std::vector<std::uint8_t>(num_dofs, 0));
  Eigen::MatrixXd R(num_dofs, num_dofs);
  for (int c = 0; c < num_dofs; ++c)
    for (int r = 0; r < num_dofs; ++r) R(r, c) = unit(rng);
  const Eigen::MatrixXd A_u =
      R * R.transpose() * 1e-3 + 1e-2 * Eigen::MatrixXd::Identity(num_dofs, num_dofs);
  const Eigen::MatrixXd J_u = Eigen::MatrixXd(p.J.J_u);
  const Eigen::MatrixXd W_body = body_scale * J_u * A_u.ldlt().solve(J_u.transpose());
  const int rows = n * rows_per_contact;
  Eigen::VectorXd body_rhs(rows);
  for (int i = 0; i < rows; ++i)
    body_rhs[i] = 0.1 * unit(rng) + (i % rows_per_contact == 0 ? press : 0.0);
  p.rows = rows_per_contact == 1
               ? MakeContactRows(p.J, W_body, body_rhs)
               : MakeFrictionContactRows(p.J, W_body, body_rhs, Eigen::VectorXd::Constant(n, mu));
  CalcDiscreteTimeWrench(p.tool, tool_state, &p.F_hat_N, &p.T_hat_N_m);
  p.F_hat_N += Eigen::Vector3d(0.3, -0.2, -3.0);  // F̃: gravity and the coupling
  p.T_hat_N_m += Eigen::Vector3d(0.01, 0.02, -0.005);
  return p;
}

// Declares the last `num_contacts` contacts of `rows` uncoupled (ContactRows::num_uncoupled_rows,
// as the visual frame sends the contacts the tool is not expected to reach): W_body becomes zero
// between each of them and every other contact's rows. With `poison`, NaN instead of zero
// there: the solvers must not read those entries (give a dense reference the zeros).
inline void UncoupleLastContacts(int num_contacts, ContactRows* rows, bool poison = false) {
  const int per = rows->rows_per_contact, n = rows->num_rows();
  rows->num_uncoupled_rows = per * num_contacts;
  const double off = poison ? std::numeric_limits<double>::quiet_NaN() : 0.0;
  for (int r = n - per * num_contacts; r < n; ++r) {
    const int own = r - r % per;
    for (int c = 0; c < n; ++c)
      if (c < own || c >= own + per) rows->W_body(r, c) = rows->W_body(c, r) = off;
  }
}

// The step's problem assembled densely, independently of the solvers' structured W:
// W = J_v A_v⁻¹ J_vᵀ + J_ω M⁻¹A_L⁻¹ J_ωᵀ + W_body (CalcToolDelassus) and rhs = body_rhs −
// J_v v_free − J_ω ω_free.
struct DenseProblem {
  Eigen::MatrixXd W;
  Eigen::VectorXd rhs;
};

inline DenseProblem AssembleDense(const ContactRows& rows, const ToolStepSystem& tool,
                                  const Eigen::Vector3d& F_hat_N,
                                  const Eigen::Vector3d& T_hat_N_m) {
  ContactJacobian J;
  J.J_v = rows.J_v;
  J.J_w = rows.J_w;
  DenseProblem dense;
  dense.W = CalcToolDelassus(J, tool) + rows.W_body;
  const Eigen::Vector3d v_free = tool.A_v.inverse() * tool.dt_s * F_hat_N;
  const Eigen::Vector3d w_free = tool.M_inv_W * tool.A_L.inverse() * tool.dt_s * T_hat_N_m;
  dense.rhs = rows.body_rhs - rows.J_v * v_free - rows.J_w * w_free;
  return dense;
}

}  // namespace hapsim::contact
