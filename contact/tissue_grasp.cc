#include "contact/tissue_grasp.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace hapsim::contact {

TissueGrasp::TissueGrasp(const GraspOptions& options, std::vector<int> candidate_nodes,
                         int num_nodes)
    : options_(options),
      candidate_nodes_(std::move(candidate_nodes)),
      is_held_(static_cast<size_t>(std::max(num_nodes, 0)), 0) {
  if (!(options.jaw_radius_m > 0.0) || !std::isfinite(options.jaw_radius_m))
    throw std::invalid_argument("TissueGrasp: the jaws' radius must be positive and finite");
  if (!(options.max_force_N > 0.0))
    throw std::invalid_argument("TissueGrasp: the grip force limit must be positive");
  for (int node : candidate_nodes_)
    if (node < 0 || node >= num_nodes)
      throw std::invalid_argument("TissueGrasp: candidate node out of range");
}

int TissueGrasp::Close(const Eigen::Isometry3d& X_WT, const Eigen::VectorXd& x_m) {
  if (closed_) return 0;
  closed_ = true;
  const Eigen::Isometry3d X_TW = X_WT.inverse();
  for (int node : candidate_nodes_) {
    const Eigen::Vector3d p_T_m = X_TW * Eigen::Vector3d(x_m.segment<3>(3 * node));
    if ((p_T_m - options_.jaw_center_T_m).norm() > options_.jaw_radius_m) continue;
    is_held_[static_cast<size_t>(node)] = 1;
    held_nodes_.push_back(node);
    held_T_m_.push_back(p_T_m);
  }
  return static_cast<int>(held_nodes_.size());
}

void TissueGrasp::Open() {
  for (int node : held_nodes_) is_held_[static_cast<size_t>(node)] = 0;
  held_nodes_.clear();
  held_T_m_.clear();
  closed_ = false;
}

void TissueGrasp::Release(int node) {
  const auto it = std::find(held_nodes_.begin(), held_nodes_.end(), node);
  if (it == held_nodes_.end()) return;
  held_T_m_.erase(held_T_m_.begin() + (it - held_nodes_.begin()));
  held_nodes_.erase(it);
  is_held_[static_cast<size_t>(node)] = 0;
}

int TissueGrasp::DropToolContactsOnHeldPoints(std::vector<Contact>* contacts) const {
  if (held_nodes_.empty()) return 0;
  const auto touches_held = [&](const Contact& c) {
    if (!c.on_tool || c.rigid_object >= 0 || c.bilateral) return false;
    for (int k = 0; k < kMaxContactNodes && c.nodes[k] >= 0; ++k)
      if (c.weights[k] != 0.0 && Holds(c.nodes[k])) return true;
    return false;
  };
  const size_t before = contacts->size();
  contacts->erase(std::remove_if(contacts->begin(), contacts->end(), touches_held),
                  contacts->end());
  return static_cast<int>(before - contacts->size());
}

void TissueGrasp::AddContacts(const Eigen::Isometry3d& X_WT, const Eigen::VectorXd& x_m,
                              std::vector<Contact>* contacts) const {
  for (size_t h = 0; h < held_nodes_.size(); ++h) {
    const int node = held_nodes_[h];
    const Eigen::Vector3d p_tool_W_m = X_WT * held_T_m_[h];
    const Eigen::Vector3d p_body_W_m = x_m.segment<3>(3 * node);
    for (int axis = 0; axis < 3; ++axis) {
      Contact contact;
      contact.p_tool_W_m = p_tool_W_m;
      contact.p_body_W_m = p_body_W_m;
      contact.n_W = X_WT.linear().col(axis);
      contact.gap_m = (p_body_W_m - p_tool_W_m).dot(contact.n_W);
      contact.SetBodyNodes({node}, {1.0});
      contact.bilateral = true;
      contacts->push_back(contact);
    }
  }
}

int TissueGrasp::LetSlip(const std::vector<Contact>& contacts, const Eigen::VectorXd& lambda_N) {
  if (held_nodes_.empty() || std::isinf(options_.max_force_N)) return 0;
  std::vector<int> slipping;
  for (size_t i = 0; i + 2 < contacts.size(); ++i) {
    if (!contacts[i].bilateral) continue;
    // A held node's three rows are consecutive (AddContacts).
    const auto row = static_cast<Eigen::Index>(i);
    const double grip_N = lambda_N.segment<3>(row).norm();
    if (grip_N > options_.max_force_N) slipping.push_back(contacts[i].nodes[0]);
    i += 2;
  }
  for (int node : slipping) Release(node);
  return static_cast<int>(slipping.size());
}

double TissueGrasp::MoveHeldPointsToTheJaws(const Eigen::Isometry3d& X_WT,
                                            const Eigen::Vector3d& v_W_m_s,
                                            const Eigen::Vector3d& w_W_rad_s, Eigen::VectorXd* x_m,
                                            Eigen::VectorXd* v_m_s) const {
  double moved_m = 0.0;
  for (size_t h = 0; h < held_nodes_.size(); ++h) {
    const int node = held_nodes_[h];
    const Eigen::Vector3d p_W_m = X_WT * held_T_m_[h];
    moved_m = std::max(moved_m, (p_W_m - x_m->segment<3>(3 * node)).norm());
    x_m->segment<3>(3 * node) = p_W_m;
    v_m_s->segment<3>(3 * node) = v_W_m_s + w_W_rad_s.cross(p_W_m - X_WT.translation());
  }
  return moved_m;
}

}  // namespace hapsim::contact
