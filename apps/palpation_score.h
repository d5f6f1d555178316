#pragma once
// The score of a palpation task (config::TaskScene; `hapsim train`, `hapsim view --score`),
// counted from the run's haptic states, one per haptic step, so that the live trainer and a log
// of the run give the same score.
//
// A target is touched while the haptic tool (the one the trainee feels) reaches into the target's
// ball: the tool's signed distance at the ball's centre is at most its radius. It is reached once
// it has been touched with the device force inside the band for hold_s without a break. Also
// counted: the time to reach every target, the peak device force, the time above the force limit
// and the haptic tool's path length (on samples every 10 haptic steps).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "config/scene.h"
#include "contact/tool_distance.h"
#include "messages/adapters.h"

namespace hapsim::apps {

class PalpationScorer {
 public:
  PalpationScorer(const config::TaskScene& task, const ToolShape& tool, double haptic_dt_s);

  // The next haptic state of the run (steps in order). Up to kMaxGapSteps missing steps (lost
  // datagrams) count as the state that follows them; a longer gap breaks a hold.
  void Add(const hapsim_lcm::haptic_state_t& state);

  std::int64_t last_step() const { return last_step_; }  // −1 before the first
  double elapsed_s() const { return (last_step_ + 1) * haptic_dt_s_; }
  bool completed() const { return num_reached_ == static_cast<int>(task_.targets.size()); }
  bool over_limit() const { return over_limit_; }  // at the last step
  std::vector<bool> reached() const;
  // One line for the screen: targets, force, warnings.
  std::string StatusLine(double force_N) const;
  nlohmann::json ToJson() const;

 private:
  struct Target {
    double hold_s = 0.0;  // in the band, touching, without a break
    bool reached = false;
    double reached_at_s = 0.0;
  };
  config::TaskScene task_;
  contact::ToolDistanceField tool_;
  double haptic_dt_s_;
  std::vector<Target> targets_;
  int num_reached_ = 0;
  std::int64_t last_step_ = -1;
  double completed_at_s_ = 0.0;
  double peak_force_N_ = 0.0;
  double time_over_limit_s_ = 0.0;
  bool over_limit_ = false;
  static constexpr std::int64_t kPathSampleSteps = 10;
  static constexpr std::int64_t kMaxGapSteps = 5;
  double path_length_m_ = 0.0;
  bool path_started_ = false;
  Eigen::Vector3d last_x_W_m_ = Eigen::Vector3d::Zero();  // at the last path sample
};

}  // namespace hapsim::apps
