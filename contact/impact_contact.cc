#include "contact/impact_contact.h"

#include <Eigen/LU>
#include <algorithm>
#include <stdexcept>

namespace hapsim::contact {

namespace {

// The parameters, checked before anything is sized from them.
const ImpactParams& Checked(const ImpactParams& params) {
  if (!(params.restitution >= 0.0 && params.restitution <= 1.0))
    throw std::invalid_argument("impact restitution must be in [0, 1]");
  if (!(params.rest_speed_m_s >= 0.0)) throw std::invalid_argument("impact rest speed < 0");
  if (params.max_contacts < 1) throw std::invalid_argument("impact max_contacts < 1");
  if (params.max_iterations < 1) throw std::invalid_argument("impact max_iterations < 1");
  if (!(params.tolerance_m_s >= 0.0)) throw std::invalid_argument("impact tolerance < 0");
  return params;
}

// Contacts ordered by depth when there are more than the rows: room for this many without a
// reallocation in the step (the geometric modes' contact buffer holds 512).
constexpr std::size_t kOrderCapacity = 4096;

}  // namespace

ImpactContact::ImpactContact(const ImpactParams& params)
    : params_(Checked(params)),
      a_(3, params.max_contacts),
      ra_(3, params.max_contacts),
      gv_(3, params.max_contacts),
      gw_(3, params.max_contacts),
      W_(params.max_contacts, params.max_contacts),
      s_(params.max_contacts),
      target_(params.max_contacts),
      lambda_(params.max_contacts) {
  order_.reserve(kOrderCapacity);
}

void ImpactContact::Calc(const std::vector<Contact>& contacts, const ToolStepSystem& system,
                         const ToolModel& model, const ToolState& tool, Eigen::Vector3d* F_W_N,
                         Eigen::Vector3d* T_W_N_m) {
  F_W_N->setZero();
  T_W_N_m->setZero();
  const int num = static_cast<int>(contacts.size());
  n_ = std::min(num, params_.max_contacts);
  num_impacts_ = 0;
  if (n_ == 0) return;
  // More contacts than rows: the deepest ones (order_ grows only past its reserve).
  order_.resize(num);
  for (int i = 0; i < num; ++i) order_[i] = i;
  if (num > n_) {
    std::partial_sort(order_.begin(), order_.begin() + n_, order_.end(),
                      [&](int i, int j) { return contacts[i].gap_m < contacts[j].gap_m; });
  }
  const double dt = system.dt_s;
  const Eigen::Matrix3d A_v_inv = system.A_v.inverse();
  const Eigen::Matrix3d M_inv = CalcWorldInverseInertia(model, tool.q_WT);
  const Eigen::Matrix3d MA_L_inv = M_inv * system.A_L.inverse();
  const Eigen::Vector3d w = M_inv * tool.L_W_kg_m2_s;
  const Eigen::Vector3d v_free = tool.v_W_m_s + A_v_inv * (dt * system.F_tilde_N);
  const Eigen::Vector3d w_free =
      M_inv * (tool.L_W_kg_m2_s + system.A_L.inverse() * (dt * system.T_tilde_N_m));
  const double e = params_.restitution;
  for (int k = 0; k < n_; ++k) {
    const Contact& c = contacts[order_[k]];
    const Eigen::Vector3d a = -c.n_W;
    const Eigen::Vector3d ra = (c.p_tool_W_m - tool.x_W_m).cross(a);
    a_.col(k) = a;
    ra_.col(k) = ra;
    gv_.col(k) = A_v_inv * a;
    gw_.col(k) = MA_L_inv * ra;
    const double s = a.dot(tool.v_W_m_s) + ra.dot(w);
    const double s_free = a.dot(v_free) + ra.dot(w_free);
    const bool impact = s < -params_.rest_speed_m_s && c.gap_m + s_free * dt <= 0.0;
    target_(k) = impact ? -e * s : -c.gap_m / dt;
    num_impacts_ += impact ? 1 : 0;
    s_(k) = s_free;
    lambda_(k) = 0.0;
  }
  for (int i = 0; i < n_; ++i) {
    for (int j = 0; j < n_; ++j)
      W_(i, j) = dt * (a_.col(i).dot(gv_.col(j)) + ra_.col(i).dot(gw_.col(j)));
  }
  SolveRows();
  for (int i = 0; i < n_; ++i) {
    *F_W_N += lambda_(i) * a_.col(i);
    *T_W_N_m += lambda_(i) * ra_.col(i);
  }
}

// Projected Gauss–Seidel on s⁺ = s_free + W λ ≥ target, λ ≥ 0, complementary; s_ holds s⁺.
void ImpactContact::SolveRows() {
  for (int sweep = 0; sweep < params_.max_iterations; ++sweep) {
    double worst_m_s = 0.0;
    for (int i = 0; i < n_; ++i) {
      const double miss = target_(i) - s_(i);
      const double lambda_new = std::max(0.0, lambda_(i) + miss / W_(i, i));
      const double change = lambda_new - lambda_(i);
      if (change != 0.0) {
        s_.head(n_) += change * W_.col(i).head(n_);
        lambda_(i) = lambda_new;
      }
      // Residual: a missed target, or a force on a contact that is over-satisfied.
      worst_m_s = std::max(worst_m_s, lambda_(i) > 0.0 ? std::abs(miss) : std::max(miss, 0.0));
    }
    if (worst_m_s <= params_.tolerance_m_s) break;
  }
}

}  // namespace hapsim::contact
