#include "contact/haptic_contact_rows.h"

#include <Eigen/LU>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <stdexcept>

namespace hapsim::contact {

void StampNewContactRows(ContactRows* rows) {
  static std::atomic<std::uint64_t> last_stamp{0};
  rows->stamp = ++last_stamp;
}

ContactRowCache::ContactRowCache(int max_rows)
    : W(max_rows, max_rows), U(max_rows, 6), body_rhs(max_rows), mu(max_rows / 3 + 1) {}

bool ContactRowCache::Holds(const ContactRows& rows) const {
  const int m = rows.num_rows();
  if (m != n || rows.num_coupled_rows() != coupled || rows.rows_per_contact != per ||
      rows.num_bilateral_rows != bilateral)
    return false;
  if (rows.stamp != 0) return rows.stamp == stamp;
  // Empty rows have null data(), which memcmp must not be given even for 0 bytes.
  const auto same = [](const double* a, const double* b, Eigen::Index size) {
    return size == 0 || std::memcmp(a, b, sizeof(double) * size) == 0;
  };
  if (rows.friction_coefficient.size() != num_mu ||
      !same(mu.data(), rows.friction_coefficient.data(), num_mu) ||
      !same(body_rhs.data(), rows.body_rhs.data(), m))
    return false;
  for (int c = 0; c < 3; ++c)
    if (!same(U.col(c).data(), rows.J_v.col(c).data(), m) ||
        !same(U.col(3 + c).data(), rows.J_w.col(c).data(), m))
      return false;
  for (int c = 0; c < coupled; ++c)
    if (!same(W.col(c).data(), rows.W_body.col(c).data(), coupled)) return false;
  for (int c = coupled; c < m; ++c) {
    const int own = FirstRowOfBlock(c, coupled, per);
    if (!same(W.col(c).data() + own, rows.W_body.col(c).data() + own, per)) return false;
  }
  return true;
}

bool ContactRowCache::Take(const ContactRows& rows) {
  n = rows.num_rows();
  coupled = rows.num_coupled_rows();
  per = rows.rows_per_contact;
  bilateral = rows.num_bilateral_rows;
  stamp = rows.stamp;
  num_mu = static_cast<int>(rows.friction_coefficient.size());
  body_rhs.head(n) = rows.body_rhs;
  mu.head(num_mu) = rows.friction_coefficient;
  U.topLeftCorner(n, 3) = rows.J_v;
  U.topRightCorner(n, 3) = rows.J_w;
  W.topLeftCorner(coupled, coupled) = rows.W_body.topLeftCorner(coupled, coupled);
  for (int a = coupled; a < n; a += per)
    W.block(a, a, per, per) = rows.W_body.block(a, a, per, per);
  // One pass over the lower triangle and its mirror: the largest entry, the largest asymmetry,
  // and a sum that is finite iff every entry is (NaN escapes the max, not the sum).
  constexpr double kSymmetryTolerance = 1e-9;
  double scale = 0.0, asymmetry = 0.0, sum = 0.0;
  for (int j = 0; j < n; ++j) {
    const int last = j < coupled ? coupled : FirstRowOfBlock(j, coupled, per) + per;  // block end
    for (int i = j; i < last; ++i) {
      const double lower = W(i, j), upper = W(j, i);
      sum += lower + upper;
      scale = std::max(scale, std::abs(lower));
      asymmetry = std::max(asymmetry, std::abs(lower - upper));
    }
  }
  const bool ok = std::isfinite(sum) && body_rhs.head(n).allFinite() && U.topRows(n).allFinite() &&
                  asymmetry <= kSymmetryTolerance * scale &&
                  (rows.lambda_frame_N.size() == 0 || rows.lambda_frame_N.allFinite());
  if (!ok) n = -1;  // nothing cached
  return ok;
}

void ContactRowCache::MultiplyBody(const Eigen::Ref<const Eigen::VectorXd>& x,
                                   Eigen::Ref<Eigen::VectorXd> y) const {
  y.head(coupled).noalias() = W.topLeftCorner(coupled, coupled) * x.head(coupled);
  for (int a = coupled; a < n; a += per)
    y.segment(a, per).noalias() = W.block(a, a, per, per) * x.segment(a, per);
}

void ContactRowCache::AddContactColumns(int a, const Eigen::Vector3d& delta,
                                        Eigen::Ref<Eigen::VectorXd> y) const {
  if (a < coupled)
    y.head(coupled).noalias() += W.block(0, a, coupled, 3) * delta;
  else
    y.segment<3>(a).noalias() += W.block<3, 3>(a, a) * delta;
}

ContactRows MakeContactRows(const ContactJacobian& J, const Eigen::MatrixXd& W_body,
                            const Eigen::VectorXd& body_rhs) {
  std::vector<int> rows(J.num_rows());
  for (int i = 0; i < J.num_rows(); ++i) rows[i] = i;
  return MakeContactRows(J, W_body, rows, body_rhs);
}

ContactRows MakeContactRows(const ContactJacobian& J, const Eigen::MatrixXd& W_body_all,
                            const std::vector<int>& rows, const Eigen::VectorXd& body_rhs,
                            const Eigen::VectorXd& friction_coefficient, int num_coupled_rows) {
  if (J.rows_per_contact != 1 && J.rows_per_contact != 3)
    throw std::invalid_argument("MakeContactRows: 1 (normal) or 3 (friction) rows per contact");
  const int n = J.num_rows();
  if (static_cast<int>(rows.size()) != n || body_rhs.size() != n || J.J_w.rows() != n)
    throw std::invalid_argument("MakeContactRows: J, rows and body_rhs differ in size");
  if (W_body_all.rows() != W_body_all.cols())
    throw std::invalid_argument("MakeContactRows: W_body must be square");
  for (int row : rows)
    if (row < 0 || row >= W_body_all.rows())
      throw std::invalid_argument("MakeContactRows: row index outside W_body");
  if (J.rows_per_contact == 3) {
    if (friction_coefficient.size() * 3 != n)
      throw std::invalid_argument("MakeContactRows: one friction coefficient per contact");
    if (!(friction_coefficient.array() >= 0.0).all())
      throw std::invalid_argument("MakeContactRows: a friction coefficient is negative");
  } else if (friction_coefficient.size() != 0) {
    throw std::invalid_argument("MakeContactRows: friction coefficients need friction rows");
  }
  const int per = J.rows_per_contact;
  const int coupled = num_coupled_rows < 0 ? n : num_coupled_rows;
  if (coupled > n || coupled % per != 0)
    throw std::invalid_argument("MakeContactRows: coupled rows must be whole contacts of the rows");
  ContactRows out;
  out.J_v = J.J_v;
  out.J_w = J.J_w;
  out.body_rhs = body_rhs;
  out.num_uncoupled_rows = n - coupled;
  // The lower triangle where rows couple, then its mirror: each entry gathered once (the whole
  // gather read W_body_all(rows[c], rows[r]) across its columns, and 720 friction rows took 0.7 ms
  // with the uncoupled entries zeroed after; about 0.3 ms now, 2026-11-27).
  // The mirror only where the lower triangle was set: a transpose of the whole n × n (block_press,
  // ~74 of ~213 contacts coupled): 0.04 → 0.03 ms here.
  out.W_body.setZero(n, n);
  for (int c = 0; c < n; ++c) {
    const int end = c < coupled ? coupled : FirstRowOfBlock(c, coupled, per) + per;
    for (int r = c; r < end; ++r)
      out.W_body(r, c) = 0.5 * (W_body_all(rows[r], rows[c]) + W_body_all(rows[c], rows[r]));
    for (int r = c + 1; r < end; ++r) out.W_body(c, r) = out.W_body(r, c);
  }
  out.rows_per_contact = per;
  out.friction_coefficient = friction_coefficient;
  return out;
}

ContactRows MakeFrictionContactRows(const ContactJacobian& J, const Eigen::MatrixXd& W_body,
                                    const Eigen::VectorXd& body_rhs,
                                    const Eigen::VectorXd& friction_coefficient) {
  if (J.rows_per_contact != 3)
    throw std::invalid_argument("MakeFrictionContactRows: needs 3 rows per contact (friction)");
  std::vector<int> rows(J.num_rows());
  for (int i = 0; i < J.num_rows(); ++i) rows[i] = i;
  return MakeContactRows(J, W_body, rows, body_rhs, friction_coefficient);
}

bool CalcToolCompliance(const ToolStepSystem& tool, const Eigen::Vector3d& F_hat_N,
                        const Eigen::Vector3d& T_hat_N_m, Eigen::Matrix<double, 6, 6>* S,
                        Eigen::Matrix<double, 6, 1>* s_free) {
  S->setZero();
  S->topLeftCorner<3, 3>() = tool.A_v.inverse();
  S->bottomRightCorner<3, 3>() = tool.M_inv_W * tool.A_L.inverse();
  s_free->head<3>() = S->topLeftCorner<3, 3>() * (tool.dt_s * F_hat_N);
  s_free->tail<3>() = S->bottomRightCorner<3, 3>() * (tool.dt_s * T_hat_N_m);
  return S->allFinite() && s_free->allFinite();
}

bool HasConsistentShape(const ContactRows& rows) {
  const Eigen::Index n = rows.num_rows();
  if (rows.J_w.rows() != n || rows.W_body.rows() != n || rows.W_body.cols() != n ||
      rows.body_rhs.size() != n ||
      (rows.lambda_frame_N.size() != 0 && rows.lambda_frame_N.size() != n) ||
      (rows.gap_m.size() != 0 && rows.gap_m.size() != n) ||
      rows.gap_target_m_s.size() != rows.gap_m.size() ||
      rows.surface_velocity_m_s.size() != rows.gap_m.size())
    return false;
  if (rows.num_uncoupled_rows < 0 || rows.num_uncoupled_rows > n ||
      rows.num_uncoupled_rows % std::max(rows.rows_per_contact, 1) != 0)
    return false;
  if (rows.num_bilateral_rows < 0 || rows.num_bilateral_rows > rows.num_coupled_rows() ||
      (rows.num_bilateral_rows > 0 && rows.rows_per_contact != 1))
    return false;
  if (rows.rows_per_contact == 1) return rows.friction_coefficient.size() == 0;
  return rows.rows_per_contact == 3 && rows.friction_coefficient.size() * 3 == n &&
         (rows.friction_coefficient.array() >= 0.0).all() && rows.friction_coefficient.allFinite();
}

}  // namespace hapsim::contact
