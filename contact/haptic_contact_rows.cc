#include "contact/haptic_contact_rows.h"

#include <stdexcept>

namespace hapsim::contact {

ContactRows MakeContactRows(const ContactJacobian& J, const Eigen::MatrixXd& W_body,
                            const Eigen::VectorXd& body_rhs) {
  std::vector<int> rows(J.num_rows());
  for (int i = 0; i < J.num_rows(); ++i) rows[i] = i;
  return MakeContactRows(J, W_body, rows, body_rhs);
}

ContactRows MakeContactRows(const ContactJacobian& J, const Eigen::MatrixXd& W_body_all,
                            const std::vector<int>& rows, const Eigen::VectorXd& body_rhs) {
  if (J.rows_per_contact != 1)
    throw std::invalid_argument("MakeContactRows: the lcp mode takes normal rows only");
  const int n = J.num_rows();
  if (static_cast<int>(rows.size()) != n || body_rhs.size() != n || J.J_w.rows() != n)
    throw std::invalid_argument("MakeContactRows: J, rows and body_rhs differ in size");
  if (W_body_all.rows() != W_body_all.cols())
    throw std::invalid_argument("MakeContactRows: W_body must be square");
  for (int row : rows)
    if (row < 0 || row >= W_body_all.rows())
      throw std::invalid_argument("MakeContactRows: row index outside W_body");
  ContactRows out;
  out.J_v = J.J_v;
  out.J_w = J.J_w;
  out.body_rhs = body_rhs;
  out.W_body.resize(n, n);
  for (int c = 0; c < n; ++c)
    for (int r = 0; r < n; ++r)
      out.W_body(r, c) = 0.5 * (W_body_all(rows[r], rows[c]) + W_body_all(rows[c], rows[r]));
  return out;
}

}  // namespace hapsim::contact
