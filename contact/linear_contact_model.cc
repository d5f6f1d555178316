#include "contact/linear_contact_model.h"

#include <Eigen/LU>
#include <Eigen/QR>
#include <stdexcept>

namespace hapsim::contact {

Eigen::MatrixXd CalcToolDelassus(const ContactJacobian& J, const ToolStepSystem& tool) {
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(J.num_rows(), J.num_rows());
  AddToolDelassus(J, tool, &W);
  return W;
}

void AddToolDelassus(const ContactJacobian& J, const ToolStepSystem& tool, Eigen::MatrixXd* W) {
  const Eigen::Index n = J.num_rows();
  if (W->rows() != n || W->cols() != n)
    throw std::invalid_argument("AddToolDelassus: W must be rows x rows of J");
  ToolDelassusColumns(J, tool).AddAll(W);
}

ToolDelassusColumns::ToolDelassusColumns(const ContactJacobian& J, const ToolStepSystem& tool)
    : J_tool_(J.num_rows(), 6), J_tool_S_(J.num_rows(), 6) {
  J_tool_ << J.J_v, J.J_w;
  J_tool_S_.leftCols<3>().noalias() = J.J_v * tool.A_v.inverse().transpose();
  J_tool_S_.rightCols<3>().noalias() = J.J_w * (tool.M_inv_W * tool.A_L.inverse()).transpose();
}

void ToolDelassusColumns::AddColumn(Eigen::Index col, Eigen::MatrixXd* W,
                                    const std::vector<std::uint8_t>* skip) const {
  if (skip == nullptr) {
    W->col(col).noalias() += J_tool_ * J_tool_S_.row(col).transpose();
    return;
  }
  const Eigen::Matrix<double, 6, 1> s = J_tool_S_.row(col).transpose();
  for (Eigen::Index r = 0; r < J_tool_.rows(); ++r)
    if (!(*skip)[static_cast<size_t>(r)]) (*W)(r, col) += J_tool_.row(r).dot(s);
}

void ToolDelassusColumns::AddDiagonal(Eigen::VectorXd* diagonal) const {
  *diagonal += J_tool_.cwiseProduct(J_tool_S_).rowwise().sum();
}

// One rank-6 product [J_v J_ω] S [J_v J_ω]ᵀ: a single pass over W (two rank-3 products and their
// sum made three, and two n × n temporaries: 0.9 ms of block_press_friction's 720-row frame).
void ToolDelassusColumns::AddAll(Eigen::MatrixXd* W) const {
  W->noalias() += J_tool_ * J_tool_S_.transpose();
}

LinearContactModel MakeLinearContactModel(const ContactJacobian& J, const Eigen::MatrixXd& W,
                                          const ToolStepSystem& tool,
                                          const Eigen::VectorXd& body_rhs) {
  LinearContactModel model;
  model.num_contacts = J.num_rows() / J.rows_per_contact;
  if (J.num_rows() == 0) return model;
  // The seven right-hand sides [J_v J_ω b − J_u u̇] in one solve. A partial-pivoting LU first
  // (2n³/3 flops): the unilateral solver's active set leaves W nonsingular. Two contacts with the
  // same body point and normal (equality constraints, or more than six on a rigid part) make W
  // singular; the LU's residual then shows it, and the rank-revealing complete orthogonal
  // decomposition (several times slower) gives the minimum-norm solution, which shares the force
  // between them.
  const Eigen::Index n = W.rows();
  Eigen::MatrixXd B(n, 7);
  B << J.J_v, J.J_w, body_rhs;
  Eigen::MatrixXd Y = Eigen::PartialPivLU<Eigen::MatrixXd>(W).solve(B);
  if (!Y.allFinite() || (W * Y - B).norm() > 1e-10 * B.norm())
    Y = Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd>(W).solve(B);
  const Eigen::MatrixX3d Y_v = Y.leftCols<3>();         // W⁻¹ J_v
  const Eigen::MatrixX3d Y_w = Y.middleCols<3>(3);      // W⁻¹ J_ω
  const Eigen::VectorXd y_0 = Y.col(6) / tool.dt_s;     // W⁻¹ (b − J_u u̇) / Δt
  const Eigen::Matrix3d A_v_inv = tool.A_v.inverse();
  const Eigen::Matrix3d M_inv_A_L_inv = tool.M_inv_W * tool.A_L.inverse();
  model.F_c0_N = J.J_v.transpose() * y_0;
  model.T_c0_N_m = J.J_w.transpose() * y_0;
  model.dFc_dF = -J.J_v.transpose() * Y_v * A_v_inv;
  model.dTc_dF = -J.J_w.transpose() * Y_v * A_v_inv;
  model.dFc_dT = -J.J_v.transpose() * Y_w * M_inv_A_L_inv;
  model.dTc_dT = -J.J_w.transpose() * Y_w * M_inv_A_L_inv;
  return model;
}

void EvaluateLinearContactModel(const LinearContactModel& model, const Eigen::Vector3d& F_hat_N,
                                const Eigen::Vector3d& T_hat_N_m, Eigen::Vector3d* F_c_N,
                                Eigen::Vector3d* T_c_N_m) {
  *F_c_N = model.F_c0_N + model.dFc_dF * F_hat_N + model.dFc_dT * T_hat_N_m;
  *T_c_N_m = model.T_c0_N_m + model.dTc_dF * F_hat_N + model.dTc_dT * T_hat_N_m;
}

void CalcDiscreteTimeWrench(const ToolStepSystem& tool, const ToolState& state,
                            Eigen::Vector3d* F_hat_N, Eigen::Vector3d* T_hat_N_m) {
  *F_hat_N = tool.F_tilde_N + tool.A_v * state.v_W_m_s / tool.dt_s;
  *T_hat_N_m = tool.T_tilde_N_m + tool.A_L * state.L_W_kg_m2_s / tool.dt_s;
}

}  // namespace hapsim::contact
