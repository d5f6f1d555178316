#include "contact/contact_jacobian.h"

#include <Eigen/Geometry>
#include <stdexcept>

namespace hapsim::contact {

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
      for (int k = 0; k < kMaxContactNodes; ++k) {
        if (contact.nodes[k] < 0 || contact.weights[k] == 0.0) continue;
        for (int a = 0; a < 3; ++a) {
          const int dof = 3 * contact.nodes[k] + a;
          if (dof_is_fixed[dof]) continue;  // a fixed node does not move: no velocity term
          body_entries.emplace_back(row, dof, contact.weights[k] * directions[d][a]);
        }
      }
    }
  }
  J.J_u.resize(num_rows, num_dofs);
  J.J_u.setFromTriplets(body_entries.begin(), body_entries.end());
  return J;
}

}  // namespace hapsim::contact
