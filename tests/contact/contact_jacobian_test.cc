// CalcContactJacobian against the definition in contact/contact_jacobian.h, written out densely
// entry by entry: J_u,i = Σ_k w_k d_iᵀ at node k's dofs (d the row's direction), none at a fixed
// dof, an entry of a node listed twice in one contact summed.
#include "contact/contact_jacobian.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <vector>

namespace hapsim::contact {
namespace {

// Row i's dense J_u from its contact, one node slot at a time.
Eigen::MatrixXd DenseBodyRows(const std::vector<Contact>& contacts, int rows_per_contact,
                              int num_dofs, const std::vector<std::uint8_t>& dof_is_fixed) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows_per_contact * contacts.size(), num_dofs);
  for (size_t i = 0; i < contacts.size(); ++i) {
    Eigen::Vector3d d[3] = {contacts[i].n_W, {}, {}};
    CalcTangents(contacts[i].n_W, &d[1], &d[2]);
    for (int r = 0; r < rows_per_contact; ++r)
      for (int k = 0; k < kMaxContactNodes && contacts[i].nodes[k] >= 0; ++k)
        for (int a = 0; a < 3; ++a) {
          const int dof = 3 * contacts[i].nodes[k] + a;
          if (!dof_is_fixed[dof])
            J(rows_per_contact * i + r, dof) += contacts[i].weights[k] * d[r][a];
        }
  }
  return J;
}

TEST(ContactJacobian, BodyRowsMatchTheDefinitionWithRepeatedAndFixedNodes) {
  const int num_nodes = 9, num_dofs = 3 * num_nodes;
  std::vector<std::uint8_t> fixed(num_dofs, 0);
  fixed[3 * 2 + 1] = 1;  // node 2's y
  std::vector<Contact> contacts(4);
  contacts[0].SetBodyNodes({5, 1, 8}, {0.2, 0.3, 0.5});    // nodes out of order
  contacts[1].SetBodyNodes({4, 6, 4}, {0.25, 0.5, 0.25});  // node 4 twice: its entries add up
  contacts[2].SetBodyNodes({2}, {1.0});                    // a partly fixed node
  contacts[3].SetBodyNodes({7, 3}, {0.0, 1.0});            // a zero weight: no entry
  contacts[0].n_W = Eigen::Vector3d(1, 2, 3).normalized();
  contacts[1].n_W = Eigen::Vector3d(0, 0, 1);
  contacts[2].n_W = Eigen::Vector3d(-1, 1, 0).normalized();
  contacts[3].n_W = Eigen::Vector3d(0.3, -1, 0.2).normalized();
  for (int rows_per_contact : {1, 3}) {
    const ContactJacobian J =
        CalcContactJacobian(contacts, Eigen::Vector3d::Zero(), rows_per_contact, num_dofs, fixed);
    ASSERT_TRUE(J.J_u.isCompressed());
    const Eigen::MatrixXd expected = DenseBodyRows(contacts, rows_per_contact, num_dofs, fixed);
    EXPECT_LT((Eigen::MatrixXd(J.J_u) - expected).cwiseAbs().maxCoeff(), 1e-15);
    // Each column's rows sorted and stored once (what Eigen's sparse products assume), and no
    // entry at a fixed dof or for the zero weight.
    for (int j = 0; j < num_dofs; ++j) {
      int last_row = -1;
      for (Eigen::SparseMatrix<double>::InnerIterator it(J.J_u, j); it; ++it) {
        EXPECT_GT(it.row(), last_row) << "column " << j;
        last_row = static_cast<int>(it.row());
      }
      if (fixed[j] || j / 3 == 7) {
        EXPECT_EQ(J.J_u.col(j).nonZeros(), 0) << "column " << j;
      }
    }
  }
}

// SelectRows against the second way to the same rows: the Jacobian of the selected contacts,
// in the selection's (permuted) order, computed anew.
TEST(ContactJacobian, SelectedRowsAreTheSelectedContactsJacobian) {
  const int num_nodes = 12, num_dofs = 3 * num_nodes;
  const std::vector<std::uint8_t> fixed(num_dofs, 0);
  std::vector<Contact> contacts(6);
  for (int i = 0; i < 6; ++i) {
    contacts[i].SetBodyNodes({(5 * i) % num_nodes, (5 * i + 3) % num_nodes, 4}, {0.5, 0.3, 0.2});
    contacts[i].n_W = Eigen::Vector3d(0.1 * i, 1.0 - 0.2 * i, 0.5).normalized();
    contacts[i].p_tool_W_m = Eigen::Vector3d(0.01 * i, -0.02, 0.003 * i);
  }
  const Eigen::Vector3d x_tool_W_m(0.0, 0.01, 0.05);
  const std::vector<int> chosen = {4, 0, 5, 2};  // contacts, out of order
  std::vector<Contact> subset;
  for (int i : chosen) subset.push_back(contacts[i]);
  for (int per : {1, 3}) {
    const ContactJacobian J_all = CalcContactJacobian(contacts, x_tool_W_m, per, num_dofs, fixed);
    std::vector<int> rows;
    for (int i : chosen)
      for (int d = 0; d < per; ++d) rows.push_back(per * i + d);
    const ContactJacobian S = SelectRows(J_all, rows);
    const ContactJacobian expected = CalcContactJacobian(subset, x_tool_W_m, per, num_dofs, fixed);
    EXPECT_EQ(S.rows_per_contact, per);
    EXPECT_EQ(S.J_v, expected.J_v);
    EXPECT_EQ(S.J_w, expected.J_w);
    EXPECT_EQ(Eigen::MatrixXd(S.J_u), Eigen::MatrixXd(expected.J_u));
    for (int j = 0; j < num_dofs; ++j) {  // the rows of each column sorted
      int last_row = -1;
      for (Eigen::SparseMatrix<double>::InnerIterator it(S.J_u, j); it; ++it) {
        EXPECT_GT(it.row(), last_row) << "column " << j;
        last_row = static_cast<int>(it.row());
      }
    }
    EXPECT_THROW(SelectRows(J_all, {0, 1, 0}), std::invalid_argument);
    EXPECT_THROW(SelectRows(J_all, {J_all.num_rows()}), std::invalid_argument);
    if (per == 3) {  // a contact's rows split, or out of order
      EXPECT_THROW(SelectRows(J_all, {1, 2, 3}), std::invalid_argument);
      EXPECT_THROW(SelectRows(J_all, {0, 2, 1}), std::invalid_argument);
    }
  }
}

}  // namespace
}  // namespace hapsim::contact
