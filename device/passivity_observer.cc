#include "device/passivity_observer.h"

#include <cmath>

namespace hapsim::device {

PassivityObserver::PassivityObserver(double threshold_J)
    : threshold_J_(threshold_J > 0.0 ? threshold_J : 0.0) {}

void PassivityObserver::Update(const Eigen::Vector3d& F, const Eigen::Vector3d& T,
                               const Eigen::Vector3d& v, const Eigen::Vector3d& w, double dt_s,
                               double gravity_work_J) noexcept {
  const long step = steps_++;
  // Hannaford & Ryu 2002: E_k = E_{k−1} − Δt (F_k·v_k + T_k·ω_k), plus gravity's work (header).
  const double power_to_hand_W = F.dot(v) + T.dot(w);
  const double energy_in_J = energy_in_J_ - dt_s * power_to_hand_W + gravity_work_J;
  // A NaN or Inf would stay in E for good (and make every later comparison false): such a
  // sample is skipped instead.
  if (!(std::isfinite(energy_in_J) && std::isfinite(dt_s) && dt_s > 0.0)) {
    ++num_ignored_;
    return;
  }
  energy_in_J_ = energy_in_J;
  if (first_active_step_ < 0 && energy_in_J_ < -threshold_J_) first_active_step_ = step;
}

}  // namespace hapsim::device
