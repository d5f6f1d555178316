#include "contact/impulse_warm_start.h"

#include <algorithm>
#include <cassert>
#include <stdexcept>
#include <utility>

#include "contact/contact_jacobian.h"

namespace hapsim::contact {

ImpulseWarmStart::ImpulseWarmStart(int rows_per_contact) : rows_per_contact_(rows_per_contact) {
  if (rows_per_contact != 1 && rows_per_contact != 3)
    throw std::invalid_argument("ImpulseWarmStart: 1 or 3 rows per contact");
}

ImpulseWarmStart::Identity ImpulseWarmStart::IdentityOf(const Contact& contact) {
  // Its surface points, not its nodes: an embedded contact's first nodes are its first point's
  // tet's, which its neighbours share.
  const std::array<int, 3>& points = contact.surface_points;
  const auto word = [](int index) {  // index ≥ −1
    assert(index >= -1);
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(index) + 1);
  };
  return {word(points[0]) << 32 | word(points[1]),
          word(points[2]) << 32 | word(contact.rigid_object) << 1 | (contact.on_tool ? 1u : 0u)};
}

namespace {

// Sorts `items` (pairs whose first is an identity) by identity and calls mark(item) on every item
// whose identity occurs more than once.
template <typename Item, typename Mark>
void SortAndMarkRepeats(std::vector<Item>* items, Mark mark) {
  std::sort(items->begin(), items->end(),
            [](const Item& a, const Item& b) { return a.first < b.first; });
  for (size_t i = 0; i < items->size();) {
    size_t end = i + 1;
    while (end < items->size() && (*items)[end].first == (*items)[i].first) ++end;
    if (end - i > 1)
      for (size_t k = i; k < end; ++k) mark(&(*items)[k]);
    i = end;
  }
}

}  // namespace

// Sorted vectors rather than a map: a map allocated a node per contact, and with ~210 contacts a
// frame Start and Record took 0.07 ms (block_press), as much as the solve they start.
void ImpulseWarmStart::Record(const std::vector<Contact>& contacts, const Eigen::VectorXd& lambda) {
  if (lambda.size() != rows_per_contact_ * static_cast<Eigen::Index>(contacts.size()))
    throw std::invalid_argument(
        "ImpulseWarmStart::Record: λ needs rows_per_contact rows a contact");
  recorded_.clear();
  for (size_t i = 0; i < contacts.size(); ++i) {
    if (!HasIdentity(contacts[i])) continue;
    const Eigen::Index row = rows_per_contact_ * static_cast<Eigen::Index>(i);
    Force force{lambda[row]};
    if (rows_per_contact_ == 3) {
      Eigen::Vector3d t1, t2;
      CalcTangents(contacts[i].n_W, &t1, &t2);
      force.tangential_W_N = lambda[row + 1] * t1 + lambda[row + 2] * t2;
    }
    recorded_.emplace_back(IdentityOf(contacts[i]), force);
  }
  SortAndMarkRepeats(&recorded_, [](std::pair<Identity, Force>* r) { r->second.ambiguous = true; });
}

Eigen::VectorXd ImpulseWarmStart::Start(const std::vector<Contact>& contacts) {
  Eigen::VectorXd lambda =
      Eigen::VectorXd::Zero(rows_per_contact_ * static_cast<Eigen::Index>(contacts.size()));
  num_carried_ = 0;
  // A recorded force goes to one contact, never to two: repeated identities take none (index −1).
  std::vector<std::pair<Identity, int>> found;
  for (size_t i = 0; i < contacts.size(); ++i)
    if (HasIdentity(contacts[i])) found.emplace_back(IdentityOf(contacts[i]), static_cast<int>(i));
  SortAndMarkRepeats(&found, [](std::pair<Identity, int>* f) { f->second = -1; });
  for (const auto& [identity, i] : found) {
    if (i < 0) continue;
    const auto it = std::lower_bound(
        recorded_.begin(), recorded_.end(), identity,
        [](const std::pair<Identity, Force>& r, const Identity& id) { return r.first < id; });
    if (it == recorded_.end() || it->first != identity || it->second.ambiguous) continue;
    const Eigen::Index row = rows_per_contact_ * static_cast<Eigen::Index>(i);
    lambda[row] = it->second.normal_N;
    if (rows_per_contact_ == 3) {
      Eigen::Vector3d t1, t2;
      CalcTangents(contacts[static_cast<size_t>(i)].n_W, &t1, &t2);
      lambda[row + 1] = t1.dot(it->second.tangential_W_N);
      lambda[row + 2] = t2.dot(it->second.tangential_W_N);
    }
    ++num_carried_;
  }
  return lambda;
}

}  // namespace hapsim::contact
