#include "contact/friction_warm_start.h"

#include <stdexcept>

#include "contact/contact_jacobian.h"

namespace hapsim::contact {

FrictionWarmStart::Identity FrictionWarmStart::IdentityOf(const Contact& contact) {
  // Its surface points, not its nodes: an embedded contact's first nodes are its first point's
  // tet's, which its neighbours share.
  const std::array<int, 3>& points = contact.surface_points;
  return {points[0], points[1], points[2], contact.rigid_object, contact.on_tool ? 1 : 0};
}

void FrictionWarmStart::Record(const std::vector<Contact>& contacts,
                               const Eigen::VectorXd& lambda) {
  if (lambda.size() != 3 * static_cast<Eigen::Index>(contacts.size()))
    throw std::invalid_argument("FrictionWarmStart::Record: 3 rows per contact");
  recorded_.clear();
  for (size_t i = 0; i < contacts.size(); ++i) {
    if (!HasIdentity(contacts[i])) continue;
    Eigen::Vector3d t1, t2;
    CalcTangents(contacts[i].n_W, &t1, &t2);
    const Eigen::Index row = 3 * static_cast<Eigen::Index>(i);
    Force force{lambda[row], lambda[row + 1] * t1 + lambda[row + 2] * t2};
    const auto [it, inserted] = recorded_.emplace(IdentityOf(contacts[i]), force);
    if (!inserted) it->second.ambiguous = true;
  }
}

Eigen::VectorXd FrictionWarmStart::Start(const std::vector<Contact>& contacts) {
  Eigen::VectorXd lambda = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(contacts.size()));
  num_carried_ = 0;
  std::map<Identity, int> count;  // a recorded force goes to one contact, never to two
  for (const Contact& contact : contacts)
    if (HasIdentity(contact)) ++count[IdentityOf(contact)];
  for (size_t i = 0; i < contacts.size(); ++i) {
    if (!HasIdentity(contacts[i]) || count[IdentityOf(contacts[i])] > 1) continue;
    const auto it = recorded_.find(IdentityOf(contacts[i]));
    if (it == recorded_.end() || it->second.ambiguous) continue;
    Eigen::Vector3d t1, t2;
    CalcTangents(contacts[i].n_W, &t1, &t2);
    const Eigen::Index row = 3 * static_cast<Eigen::Index>(i);
    lambda[row] = it->second.normal_N;
    lambda[row + 1] = t1.dot(it->second.tangential_W_N);
    lambda[row + 2] = t2.dot(it->second.tangential_W_N);
    ++num_carried_;
  }
  return lambda;
}

}  // namespace hapsim::contact
