#include "contact/collision_response.h"

#include <algorithm>

namespace hapsim::contact {

Eigen::VectorXd CalcConstraintTargets(const std::vector<Contact>& contacts,
                                      const Eigen::VectorXd& c_pre, int rows_per_contact,
                                      double dt_s, const ResponseOptions& options) {
  Eigen::VectorXd b = Eigen::VectorXd::Zero(rows_per_contact * static_cast<int>(contacts.size()));
  for (size_t i = 0; i < contacts.size(); ++i) {
    const int row = rows_per_contact * static_cast<int>(i);
    const double gap_m = contacts[i].gap_m;
    // A grasp row holds its point where the jaws took it: a fraction β of any offset, either
    // sign, is undone per frame, as a penetration is.
    if (contacts[i].bilateral) {
      b[row] = -options.stabilization_beta * gap_m / dt_s;
      continue;
    }
    b[row] = gap_m >= 0.0 ? -gap_m / dt_s : -options.stabilization_beta * gap_m / dt_s;
    const double approach_m_s = c_pre[row];
    if (options.restitution > 0.0 && approach_m_s < 0.0 && gap_m <= -approach_m_s * dt_s)
      b[row] = std::max(b[row], -options.restitution * approach_m_s);
  }
  return b;
}

std::vector<int> SelectCollidingContacts(const std::vector<Contact>& contacts,
                                         const Eigen::VectorXd& c_free, int rows_per_contact,
                                         double dt_s, double margin_m) {
  std::vector<int> kept;
  for (size_t i = 0; i < contacts.size(); ++i)
    if (contacts[i].bilateral ||
        contacts[i].gap_m + dt_s * c_free[rows_per_contact * static_cast<int>(i)] < margin_m)
      kept.push_back(static_cast<int>(i));
  return kept;
}

}  // namespace hapsim::contact
