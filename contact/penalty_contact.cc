#include "contact/penalty_contact.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <stdexcept>

namespace hapsim::contact {

Eigen::Vector3d LimitChange(const Eigen::Vector3d& previous, const Eigen::Vector3d& current,
                            double max_change) {
  const Eigen::Vector3d change = current - previous;
  const double size = change.norm();
  if (size > 2.0 * max_change) return previous + (max_change / size) * change;
  if (size > max_change) return 0.5 * (previous + current);
  return current;
}

PenaltyContact::PenaltyContact(const PenaltyParams& params, int num_objects)
    : params_(params),
      pair_depth_m_(static_cast<size_t>(num_objects) + 1, 0.0),
      pair_depth_sum_m_(static_cast<size_t>(num_objects) + 1, 0.0) {
  if (!(params.stiffness_N_m > 0.0)) throw std::invalid_argument("penalty stiffness must be > 0");
  if (!(params.max_force_change_N > 0.0) || !(params.max_torque_change_N_m > 0.0)) {
    throw std::invalid_argument("penalty force and torque change limits must be > 0");
  }
}

double PenaltyContact::CalcMargin(const Eigen::Vector3d& v_W_m_s, const Eigen::Vector3d& w_W_rad_s,
                                  double bounding_radius_m, double dt_s) const {
  if (!params_.predictive_margin) return 0.0;
  return (v_W_m_s.norm() + w_W_rad_s.norm() * bounding_radius_m) * dt_s;
}

void PenaltyContact::Calc(const std::vector<Contact>& contacts, double margin_m,
                          const Eigen::Vector3d& x_tool_W_m, Eigen::Vector3d* F_W_N,
                          Eigen::Vector3d* T_W_N_m) {
  // Pair index: the rigid object's, or the last slot for the deformable body.
  const int body_pair = static_cast<int>(pair_depth_m_.size()) - 1;
  auto pair_of = [body_pair](const Contact& c) {
    return c.rigid_object >= 0 ? c.rigid_object : body_pair;
  };
  std::fill(pair_depth_m_.begin(), pair_depth_m_.end(), 0.0);
  std::fill(pair_depth_sum_m_.begin(), pair_depth_sum_m_.end(), 0.0);
  for (const Contact& c : contacts) {
    const double depth_m = margin_m - c.gap_m;  // ε + d
    if (depth_m <= 0.0) continue;
    const int p = pair_of(c);
    pair_depth_m_[p] = std::max(pair_depth_m_[p], depth_m);
    pair_depth_sum_m_[p] += depth_m;
  }
  raw_F_W_N_.setZero();
  raw_T_W_N_m_.setZero();
  for (const Contact& c : contacts) {
    const double depth_m = margin_m - c.gap_m;
    if (depth_m <= 0.0) continue;
    const int p = pair_of(c);
    // The pair's k (ε + d), this contact's share of it; pushing the tool back along −n.
    const double f_N = params_.stiffness_N_m * pair_depth_m_[p] * depth_m / pair_depth_sum_m_[p];
    const Eigen::Vector3d f_W_N = -f_N * c.n_W;
    raw_F_W_N_ += f_W_N;
    raw_T_W_N_m_ += (c.p_tool_W_m - x_tool_W_m).cross(f_W_N);
  }
  F_W_N_ = LimitChange(F_W_N_, raw_F_W_N_, params_.max_force_change_N);
  T_W_N_m_ = LimitChange(T_W_N_m_, raw_T_W_N_m_, params_.max_torque_change_N_m);
  *F_W_N = F_W_N_;
  *T_W_N_m = T_W_N_m_;
}

}  // namespace hapsim::contact
