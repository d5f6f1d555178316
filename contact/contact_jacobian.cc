#include "contact/contact_jacobian.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <stdexcept>

#include "fem/sparse_rows.h"

namespace hapsim::contact {
namespace {

// A sparse matrix in compressed column form from its entries in row order (a row's own in any
// order): a counting sort by column, which leaves each column's rows sorted and adds up an entry
// given twice (a node listed twice in one contact): the matrix setFromTriplets makes, bit for bit,
// without its transposed copy. With the node loop below stopping at the first unused slot,
// block_press's ~210-contact Jacobian went 0.026 → 0.018 ms (a temporary stage timer, frames with
// ≥ 200 contacts).
Eigen::SparseMatrix<double> MakeColumnMajor(int num_rows, int num_cols,
                                            const std::vector<Eigen::Triplet<double>>& entries) {
  Eigen::SparseMatrix<double> M(num_rows, num_cols);
  int* starts = M.outerIndexPtr();
  std::fill_n(starts, num_cols + 1, 0);
  std::vector<int> last_row(static_cast<size_t>(num_cols), -1);  // a column's latest row
  for (const Eigen::Triplet<double>& e : entries) {
    if (last_row[e.col()] == e.row()) continue;  // the same entry again: added below
    last_row[e.col()] = e.row();
    ++starts[e.col() + 1];
  }
  for (int c = 0; c < num_cols; ++c) starts[c + 1] += starts[c];
  M.resizeNonZeros(starts[num_cols]);
  std::vector<int> next(starts, starts + num_cols);
  std::fill(last_row.begin(), last_row.end(), -1);
  int* rows = M.innerIndexPtr();
  double* values = M.valuePtr();
  for (const Eigen::Triplet<double>& e : entries) {
    const int c = e.col();
    if (last_row[c] == e.row()) {
      values[next[c] - 1] += e.value();
      continue;
    }
    last_row[c] = e.row();
    rows[next[c]] = e.row();
    values[next[c]++] = e.value();
  }
  return M;
}

}  // namespace

void CalcTangents(const Eigen::Vector3d& n, Eigen::Vector3d* t1, Eigen::Vector3d* t2) {
  // Cross with the coordinate axis least aligned with n: never near-parallel.
  Eigen::Index axis;
  n.cwiseAbs().minCoeff(&axis);
  *t1 = n.cross(Eigen::Vector3d::Unit(axis)).normalized();
  *t2 = n.cross(*t1);
}

ContactJacobian CalcContactJacobian(const std::vector<Contact>& contacts,
                                    const Eigen::Vector3d& x_tool_W_m, int rows_per_contact,
                                    int num_dofs, const std::vector<std::uint8_t>& dof_is_fixed) {
  if (rows_per_contact != 1 && rows_per_contact != 3)
    throw std::invalid_argument("rows_per_contact must be 1 or 3");
  ContactJacobian J;
  J.rows_per_contact = rows_per_contact;
  const int num_rows = rows_per_contact * static_cast<int>(contacts.size());
  J.J_v.resize(num_rows, 3);
  J.J_w.resize(num_rows, 3);
  size_t num_entries = 0;  // an upper bound: 3 per node slot used, per row
  for (const Contact& contact : contacts)
    for (int k = 0; k < kMaxContactNodes && contact.nodes[k] >= 0; ++k) num_entries += 3;
  std::vector<Eigen::Triplet<double>> body_entries;
  body_entries.reserve(num_entries * static_cast<size_t>(rows_per_contact));
  for (size_t i = 0; i < contacts.size(); ++i) {
    const Contact& contact = contacts[i];
    Eigen::Vector3d directions[3];
    directions[0] = contact.n_W;
    if (rows_per_contact == 3) CalcTangents(contact.n_W, &directions[1], &directions[2]);
    const Eigen::Vector3d r_W_m = contact.p_tool_W_m - x_tool_W_m;
    for (int d = 0; d < rows_per_contact; ++d) {
      const int row = rows_per_contact * static_cast<int>(i) + d;
      // A body node on a rigid object: neither side is the tool.
      J.J_v.row(row) = contact.on_tool ? Eigen::RowVector3d(-directions[d].transpose())
                                       : Eigen::RowVector3d::Zero();
      J.J_w.row(row) = contact.on_tool ? Eigen::RowVector3d(-r_W_m.cross(directions[d]).transpose())
                                       : Eigen::RowVector3d::Zero();
      for (int k = 0; k < kMaxContactNodes && contact.nodes[k] >= 0; ++k) {  // slots [0, k) used
        if (contact.weights[k] == 0.0) continue;
        for (int a = 0; a < 3; ++a) {
          const int dof = 3 * contact.nodes[k] + a;
          if (dof_is_fixed[dof]) continue;  // a fixed node does not move: no velocity term
          body_entries.emplace_back(row, dof, contact.weights[k] * directions[d][a]);
        }
      }
    }
  }
  J.J_u = MakeColumnMajor(num_rows, num_dofs, body_entries);
  return J;
}

// J_u's entries row by row (fem::GatherRows), taken in the new rows' order, then by column
// (MakeColumnMajor): O(entries) however many rows a column holds (an embedded surface puts many
// contacts on one tet node, where an insertion sort per column was quadratic).
ContactJacobian SelectRows(const ContactJacobian& J, const std::vector<int>& rows) {
  const Eigen::Index n = static_cast<Eigen::Index>(rows.size());
  const int per = J.rows_per_contact;
  if (n % per != 0)
    throw std::invalid_argument("SelectRows: whole contacts, rows_per_contact rows each");
  std::vector<char> taken(static_cast<size_t>(J.num_rows()), 0);
  for (Eigen::Index r = 0; r < n; ++r) {
    const int row = rows[static_cast<size_t>(r)];
    if (row < 0 || row >= J.num_rows() || taken[static_cast<size_t>(row)])
      throw std::invalid_argument("SelectRows: a row outside J or given twice");
    const int first = rows[static_cast<size_t>(r - r % per)];
    if (first % per != 0 || row != first + r % per)
      throw std::invalid_argument("SelectRows: a contact's rows must come whole and in order");
    taken[static_cast<size_t>(row)] = 1;
  }
  ContactJacobian S;
  S.rows_per_contact = per;
  S.J_v.resize(n, 3);
  S.J_w.resize(n, 3);
  for (Eigen::Index r = 0; r < n; ++r) {
    S.J_v.row(r) = J.J_v.row(rows[static_cast<size_t>(r)]);
    S.J_w.row(r) = J.J_w.row(rows[static_cast<size_t>(r)]);
  }
  const fem::SparseRows by_row = fem::GatherRows(J.J_u);
  std::vector<Eigen::Triplet<double>> entries;
  for (Eigen::Index r = 0; r < n; ++r) {
    const int row = rows[static_cast<size_t>(r)];
    for (int k = by_row.start[row]; k < by_row.start[row + 1]; ++k)
      entries.emplace_back(static_cast<int>(r), by_row.entries[k].first, by_row.entries[k].second);
  }
  S.J_u = MakeColumnMajor(static_cast<int>(n), static_cast<int>(J.J_u.cols()), entries);
  return S;
}

}  // namespace hapsim::contact
