#pragma once
// The score of a palpation task (config::TaskScene; `hapsim train`, `hapsim view --score`),
// counted from the run's haptic states, one per haptic step, so that the live trainer and a log
// of the run give the same score.
//
// A target is touched while the haptic tool (the one the trainee feels) reaches into the target's
// ball: the tool's signed distance at the ball's centre is at most its radius. It is reached once
// it has been touched with the tissue force inside the band for hold_s without a break. Also
// counted: the time to reach every target, the peak tissue force, the time above the (tissue)
// force limit and the haptic tool's path length (on samples every 10 haptic steps).
//
// A retraction task (a tool with a grasp, scenes/retraction.yaml) is the same task with targets
// where the grasped tissue is to be pulled to: a target is reached while the jaws are in its ball
// with the tissue's pull in the band (only held tissue pulls there), for hold_s. Also counted from
// the run's frames: the points that slipped from the jaws (the tissue torn).
//
// The tissue force is what the tool presses on what it touches, F_device − m g: at rest the
// coupling holds the tool against its weight and the contact (F_device = F_contact + m g, where
// F_device is the coupling's pull on the device and F_contact the tissue's push back). It is
// measured the same way in every haptic mode, coupling included (which renders no contact force
// of its own), and a tool resting in free space presses with zero, whatever its weight. A step
// the safety layer zeroed presses with zero too.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "config/scene.h"
#include "contact/tool_distance.h"
#include "messages/adapters.h"

namespace hapsim::view {

class PalpationScorer {
 public:
  // tool_weight_N: m g of the tool, world (the scene's tool mass and gravity); grasper: the tool
  // has jaws (tool.grasp), so the score says how much tissue slipped from them.
  PalpationScorer(const config::TaskScene& task, const ToolShape& tool,
                  const Eigen::Vector3d& tool_weight_N, double haptic_dt_s, bool grasper = false);

  // The next haptic state of the run (steps in order). Up to kMaxGapSteps missing steps (lost
  // datagrams) count as the state that follows them; a longer gap breaks a hold.
  void Add(const hapsim_lcm::haptic_state_t& state);

  // The grasper's counts of the visual frame `sequence` (frames in order; a repeat or an older
  // one is ignored): points held after it, points that slipped out at it.
  void AddFrame(std::int64_t sequence, int num_grasped, int num_slipped);

  std::int64_t last_step() const { return last_step_; }  // −1 before the first
  std::int64_t last_frame() const { return last_frame_; }  // −1 before the first
  int points_slipped() const { return points_slipped_; }
  double elapsed_s() const { return (last_step_ + 1) * haptic_dt_s_; }
  bool completed() const { return num_reached_ == static_cast<int>(task_.targets.size()); }
  bool over_limit() const { return over_limit_; }  // at the last step
  std::vector<bool> reached() const;
  // One line for the screen: targets, the tissue force, warnings (at the last state).
  std::string StatusLine() const;
  nlohmann::json ToJson() const;

 private:
  struct Target {
    double hold_s = 0.0;  // in the band, touching, without a break
    bool reached = false;
    double reached_at_s = 0.0;
  };
  config::TaskScene task_;
  contact::ToolDistanceField tool_;
  Eigen::Vector3d tool_weight_N_;
  double haptic_dt_s_;
  bool grasper_;
  std::vector<Target> targets_;
  int num_reached_ = 0;
  std::int64_t last_step_ = -1;
  double completed_at_s_ = 0.0;
  double peak_force_N_ = 0.0;
  double last_force_N_ = 0.0;
  double time_over_limit_s_ = 0.0;
  std::int64_t last_frame_ = -1;
  int points_held_ = 0;     // after the last frame
  int points_slipped_ = 0;  // over the run
  bool over_limit_ = false;
  static constexpr std::int64_t kPathSampleSteps = 10;
  static constexpr std::int64_t kMaxGapSteps = 5;
  double path_length_m_ = 0.0;
  bool path_started_ = false;
  Eigen::Vector3d last_x_W_m_ = Eigen::Vector3d::Zero();  // at the last path sample
};

}  // namespace hapsim::view
