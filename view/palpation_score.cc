#include "view/palpation_score.h"

#include <Eigen/Geometry>
#include <cstdio>

namespace hapsim::view {

PalpationScorer::PalpationScorer(const config::TaskScene& task, const ToolShape& tool,
                                 const Eigen::Vector3d& tool_weight_N, double haptic_dt_s,
                                 bool grasper)
    : task_(task),
      tool_(tool),
      tool_weight_N_(tool_weight_N),
      haptic_dt_s_(haptic_dt_s),
      grasper_(grasper),
      targets_(task.targets.size()) {}

void PalpationScorer::AddFrame(std::int64_t sequence, int num_grasped, int num_slipped) {
  if (sequence <= last_frame_) return;
  last_frame_ = sequence;
  points_held_ = num_grasped;
  points_slipped_ += num_slipped;
}

void PalpationScorer::Add(const hapsim_lcm::haptic_state_t& state) {
  if (state.step <= last_step_) return;  // a repeat or an older step
  // A few missing steps (datagrams lost on the way) do not break a hold; a longer gap does.
  const std::int64_t gap_steps = last_step_ < 0 ? 1 : state.step - last_step_;
  const bool consecutive = gap_steps <= kMaxGapSteps;
  const double t_s = (state.step + 1) * haptic_dt_s_;  // the end of this step
  const Eigen::Vector3d x_W_m(state.x_W_m[0], state.x_W_m[1], state.x_W_m[2]);
  const Eigen::Quaterniond q_WT(state.q_WT[0], state.q_WT[1], state.q_WT[2], state.q_WT[3]);
  // A zeroed step (the safety layer's) presses nothing: its device force is 0, not −m g.
  const double force_N =
      state.zeroed
          ? 0.0
          : (Eigen::Map<const Eigen::Vector3d>(state.force_device_W_N) - tool_weight_N_).norm();
  // The path on 10 ms samples: the haptic tool's 1 kHz jitter (tens of micrometres a step)
  // would otherwise add up to metres over a session.
  if (state.step % kPathSampleSteps == 0) {
    if (path_started_) path_length_m_ += (x_W_m - last_x_W_m_).norm();
    last_x_W_m_ = x_W_m;
    path_started_ = true;
  }
  last_step_ = state.step;
  peak_force_N_ = std::max(peak_force_N_, force_N);
  last_force_N_ = force_N;
  over_limit_ = force_N > task_.force_limit_N;
  if (over_limit_) time_over_limit_s_ += (consecutive ? gap_steps : 1) * haptic_dt_s_;
  const bool in_band = force_N >= task_.force_band_min_N && force_N <= task_.force_band_max_N;
  const Eigen::Isometry3d X_TW = (Eigen::Translation3d(x_W_m) * q_WT.normalized()).inverse();
  for (size_t i = 0; i < targets_.size(); ++i) {
    Target& target = targets_[i];
    const config::PalpationTarget& where = task_.targets[i];
    const bool touching = tool_.Calc(X_TW * where.position_m).distance_m <= where.radius_m;
    target.hold_s = touching && in_band
                        ? (consecutive ? target.hold_s + gap_steps * haptic_dt_s_ : haptic_dt_s_)
                        : 0.0;
    // 1e-9: hold_s sums hold_s / dt steps of dt, which may round just below hold_s.
    if (!target.reached && target.hold_s >= task_.hold_s - 1e-9) {
      target.reached = true;
      target.reached_at_s = t_s;
      if (++num_reached_ == static_cast<int>(targets_.size())) completed_at_s_ = t_s;
    }
  }
}

std::vector<bool> PalpationScorer::reached() const {
  std::vector<bool> reached;
  for (const Target& target : targets_) reached.push_back(target.reached);
  return reached;
}

std::string PalpationScorer::StatusLine() const {
  char text[256];
  std::snprintf(text, sizeof(text),
                "task: %d of %zu targets  %.1f / %.0f s  tissue %.2f N (band %.2f-%.2f N)%s%s",
                num_reached_, targets_.size(), elapsed_s(), task_.time_limit_s, last_force_N_,
                task_.force_band_min_N, task_.force_band_max_N,
                over_limit_ ? "   OVER THE FORCE LIMIT" : "", completed() ? "   DONE" : "");
  std::string line = text;
  if (grasper_) {
    line += "   holding " + std::to_string(points_held_) + " points";
    if (points_slipped_ > 0) line += "   TORN: " + std::to_string(points_slipped_) + " slipped";
  }
  return line;
}

nlohmann::json PalpationScorer::ToJson() const {
  nlohmann::json targets = nlohmann::json::array();
  for (size_t i = 0; i < targets_.size(); ++i) {
    nlohmann::json target{{"name", task_.targets[i].name}, {"reached", targets_[i].reached}};
    if (targets_[i].reached) target["reached_at_s"] = targets_[i].reached_at_s;
    targets.push_back(target);
  }
  nlohmann::json json{{"steps", last_step_ + 1},
                      {"elapsed_s", elapsed_s()},
                      {"targets_reached", num_reached_},
                      {"targets_total", targets_.size()},
                      {"completed", completed()},
                      {"peak_force_N", peak_force_N_},
                      {"time_over_force_limit_s", time_over_limit_s_},
                      {"force_limit_N", task_.force_limit_N},
                      {"force_band_N", {task_.force_band_min_N, task_.force_band_max_N}},
                      {"hold_s", task_.hold_s},
                      {"tool_path_length_m", path_length_m_},
                      {"targets", targets}};
  if (completed()) json["time_to_complete_s"] = completed_at_s_;
  if (grasper_) {
    json["grip_slipped_points"] = points_slipped_;
    json["tissue_torn"] = points_slipped_ > 0;
  }
  return json;
}

}  // namespace hapsim::view
