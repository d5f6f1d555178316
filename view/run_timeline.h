#pragma once
// The messages of one run by time, for pictures of it (`hapsim view`, `hapsim train`): SIM_FRAME
// by frame, HAPTIC_STATE by haptic step, DEVICE_STATE by sequence. A log fills it whole; a live
// view adds messages as they arrive. Both pick the picture at time t by the same rule (StateAt),
// so `hapsim view LOG --at t` draws what the live view drew at t.

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "messages/adapters.h"
#include "view/scene_painter.h"

namespace hapsim::view {

class RunTimeline {
 public:
  explicit RunTimeline(double haptic_dt_s) : haptic_dt_s_(haptic_dt_s) {}

  void Add(const hapsim_lcm::sim_frame_t& frame);
  void Add(const hapsim_lcm::haptic_state_t& state);  // step < 0 (waiting) is ignored
  void Add(const hapsim_lcm::device_state_t& state);
  // Drops frames, haptic and device states more than `keep_s` older than the newest (a live
  // view; a frame of 5,000 nodes holds ~0.5 MB).
  void Forget(double keep_s);

  // The picture at t: the last frame starting at or before t; the haptic state of step
  // floor(t / Δt_haptic), or the last before it; the device state that step used (its
  // device_sequence), or the last before it. has_* false where there is none.
  ViewState StateAt(double t_s) const;
  // Copies of the haptic states after `step`, in step order (a scorer's next states).
  std::vector<hapsim_lcm::haptic_state_t> HapticStatesAfter(std::int64_t step) const;
  // What the grasper did in each frame after `sequence`, in order (a scorer's count of tissue
  // slipped from the jaws), without copying the frames' meshes.
  struct GraspCount {
    std::int64_t sequence = 0;
    int num_grasped = 0;
    int num_slipped = 0;
  };
  std::vector<GraspCount> GraspCountsAfter(std::int64_t sequence) const;
  // The time of the first and the newest frame (0 and 0 without frames).
  double first_frame_s() const;
  double last_frame_s() const;
  bool has_frames() const;
  double visual_dt_s() const;  // between the first two frames; 0 with fewer

 private:
  double haptic_dt_s_;
  mutable std::mutex mutex_;  // a live view adds from its receive thread
  std::map<std::int64_t, hapsim_lcm::sim_frame_t> frames_;     // by sequence
  std::map<std::int64_t, hapsim_lcm::haptic_state_t> haptic_;  // by step
  std::map<std::int64_t, hapsim_lcm::device_state_t> device_;  // by sequence
};

// Whether a decoded SIM_FRAME can be drawn: positions finite, every triangle's nodes among the
// frame's nodes, contacts finite. Untrusted bytes (another publisher on the URL, a corrupt log)
// decode into any values; *error says what is wrong.
bool IsDrawableFrame(const hapsim_lcm::sim_frame_t& frame, std::string* error);

// A logged run: its RUN_INFO and its timeline. Reads the run `requested_run` (hex; empty: the
// log's only run) of the log at `path`; messages that do not decode are skipped and counted.
// Throws InputError naming the log (corrupt, no such run, no RUN_INFO, no SIM_FRAME).
struct LoggedRun {
  hapsim_lcm::run_info_t info;
  std::unique_ptr<RunTimeline> timeline;
  long skipped = 0;
};
LoggedRun ReadLoggedRun(const std::string& path, const std::string& requested_run);

}  // namespace hapsim::view
