#include "view/run_timeline.h"

#include <cmath>
#include <iterator>
#include <optional>
#include <vector>

#include "core/error.h"
#include "messages/channels.h"
#include "messages/lcm_log_reader.h"
#include "messages/logged_run.h"
#include "messages/wire_decode.h"

namespace hapsim::view {
namespace {

// The entry of `map` with the largest key ≤ key, or nullptr.
template <typename Value>
const Value* AtOrBefore(const std::map<std::int64_t, Value>& map, std::int64_t key) {
  auto it = map.upper_bound(key);
  if (it == map.begin()) return nullptr;
  return &std::prev(it)->second;
}

}  // namespace

void RunTimeline::Add(const hapsim_lcm::sim_frame_t& frame) {
  std::lock_guard<std::mutex> lock(mutex_);
  frames_[frame.sequence] = frame;
}

void RunTimeline::Add(const hapsim_lcm::haptic_state_t& state) {
  if (state.step < 0) return;
  std::lock_guard<std::mutex> lock(mutex_);
  haptic_[state.step] = state;
}

void RunTimeline::Add(const hapsim_lcm::device_state_t& state) {
  std::lock_guard<std::mutex> lock(mutex_);
  device_[state.sequence] = state;
}

void RunTimeline::Forget(double keep_s) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (haptic_.empty()) return;
  const std::int64_t keep_steps = std::llround(keep_s / haptic_dt_s_);
  const std::int64_t newest = haptic_.rbegin()->first;
  haptic_.erase(haptic_.begin(), haptic_.lower_bound(newest - keep_steps));
  if (!device_.empty()) {
    const std::int64_t newest_device = device_.rbegin()->first;
    device_.erase(device_.begin(), device_.lower_bound(newest_device - keep_steps));
  }
  if (!frames_.empty()) {
    const double oldest_s = frames_.rbegin()->second.t_s - keep_s;
    while (frames_.size() > 1 && frames_.begin()->second.t_s < oldest_s)
      frames_.erase(frames_.begin());
  }
}

bool IsDrawableFrame(const hapsim_lcm::sim_frame_t& frame, std::string* error) {
  for (const std::vector<float>& p : frame.positions_W_m) {
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      *error = "a node position is not finite";
      return false;
    }
  }
  for (const std::vector<int32_t>& triangle : frame.triangles) {
    for (const int32_t node : triangle) {
      if (node < 0 || node >= frame.num_nodes) {
        *error = "a triangle names node " + std::to_string(node) + " of " +
                 std::to_string(frame.num_nodes);
        return false;
      }
    }
  }
  for (int i = 0; i < frame.num_contacts; ++i) {
    for (int d = 0; d < 3; ++d) {
      if (!std::isfinite(frame.p_W_m[i][d]) || !std::isfinite(frame.n_W[i][d])) {
        *error = "a contact is not finite";
        return false;
      }
    }
  }
  for (int i = 0; i < frame.num_objects; ++i) {
    for (int d = 0; d < 4; ++d) {
      if ((d < 3 && !std::isfinite(frame.object_x_W_m[i][d])) ||
          !std::isfinite(frame.object_q_WO[i][d])) {
        *error = "a rigid object's pose is not finite";
        return false;
      }
    }
  }
  for (const int32_t node : frame.grasped_nodes) {
    if (node < 0 || node >= frame.num_nodes) {
      *error = "a grasped node " + std::to_string(node) + " of " + std::to_string(frame.num_nodes);
      return false;
    }
  }
  if (frame.num_grasp_slipped < 0) {
    *error = "a negative count of slipped grasp points";
    return false;
  }
  for (const int32_t object : {frame.selected_object, frame.grabbed_object}) {
    if (object < -1 || object >= frame.num_objects) {
      *error = "a selected or grabbed object " + std::to_string(object) + " of " +
               std::to_string(frame.num_objects);
      return false;
    }
  }
  for (const double x : {frame.x_W_m[0], frame.x_W_m[1], frame.x_W_m[2], frame.q_WT[0],
                         frame.q_WT[1], frame.q_WT[2], frame.q_WT[3], frame.t_s}) {
    if (!std::isfinite(x)) {
      *error = "the tool pose or the time is not finite";
      return false;
    }
  }
  return true;
}

ViewState RunTimeline::StateAt(double t_s) const {
  std::lock_guard<std::mutex> lock(mutex_);
  ViewState state;
  // Frame times are k·Δt_visual: a tolerance of 1 µs keeps t = k·Δt on frame k.
  for (auto it = frames_.rbegin(); it != frames_.rend(); ++it) {
    if (it->second.t_s <= t_s + 1e-6) {
      state.frame = it->second;
      state.has_frame = true;
      break;
    }
  }
  const std::int64_t step = static_cast<std::int64_t>(std::floor(t_s / haptic_dt_s_ + 1e-6));
  if (const hapsim_lcm::haptic_state_t* haptic = AtOrBefore(haptic_, step)) {
    state.haptic = *haptic;
    state.has_haptic = true;
    if (const hapsim_lcm::device_state_t* device = AtOrBefore(device_, haptic->device_sequence)) {
      state.device = *device;
      state.has_device = true;
    }
  } else if (!device_.empty()) {
    state.device = device_.begin()->second;  // before the loop ran: the device's first sample
    state.has_device = true;
  }
  return state;
}

std::vector<hapsim_lcm::haptic_state_t> RunTimeline::HapticStatesAfter(std::int64_t step) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<hapsim_lcm::haptic_state_t> states;
  for (auto it = haptic_.upper_bound(step); it != haptic_.end(); ++it) states.push_back(it->second);
  return states;
}

std::vector<RunTimeline::GraspCount> RunTimeline::GraspCountsAfter(std::int64_t sequence) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::vector<GraspCount> counts;
  for (auto it = frames_.upper_bound(sequence); it != frames_.end(); ++it)
    counts.push_back({it->first, it->second.num_grasped, it->second.num_grasp_slipped});
  return counts;
}

double RunTimeline::first_frame_s() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frames_.empty() ? 0.0 : frames_.begin()->second.t_s;
}

double RunTimeline::last_frame_s() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frames_.empty() ? 0.0 : frames_.rbegin()->second.t_s;
}

bool RunTimeline::has_frames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return !frames_.empty();
}

double RunTimeline::visual_dt_s() const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (frames_.size() < 2) return 0.0;
  return std::next(frames_.begin())->second.t_s - frames_.begin()->second.t_s;
}

LoggedRun ReadLoggedRun(const std::string& path, const std::string& requested_run) {
  const std::int64_t run_id = messages::ChooseLoggedRun(path, requested_run);
  LoggedRun run;
  std::optional<hapsim_lcm::run_info_t> info;
  // Messages before RUN_INFO wait here: the haptic step needs the rate RUN_INFO gives.
  std::vector<hapsim_lcm::sim_frame_t> frames;
  std::vector<hapsim_lcm::haptic_state_t> haptic;
  std::vector<hapsim_lcm::device_state_t> devices;
  messages::LcmLogEvent event;
  messages::LcmLogReader log(path);
  const auto decode = [&](auto* msg) {
    std::string error;
    if (messages::Decode(event.data.data(), static_cast<int>(event.data.size()), msg, &error))
      return true;
    ++run.skipped;
    return false;
  };
  while (log.Next(&event)) {
    std::int64_t id = 0;
    if (!messages::PeekRunId(event.data.data(), static_cast<int>(event.data.size()), &id) ||
        id != run_id)
      continue;
    if (event.channel == messages::kRunInfoChannel) {
      hapsim_lcm::run_info_t msg;
      if (decode(&msg)) info = std::move(msg);
    } else if (event.channel == messages::kSimFrameChannel) {
      hapsim_lcm::sim_frame_t msg;
      std::string error;
      if (!decode(&msg)) continue;
      if (IsDrawableFrame(msg, &error)) {
        frames.push_back(std::move(msg));
      } else {
        ++run.skipped;
      }
    } else if (event.channel == messages::kHapticStateChannel) {
      hapsim_lcm::haptic_state_t msg;
      if (decode(&msg)) haptic.push_back(std::move(msg));
    } else if (event.channel == messages::kDeviceStateChannel) {
      hapsim_lcm::device_state_t msg;
      if (decode(&msg)) devices.push_back(std::move(msg));
    }
  }
  if (!info) throw InputError(path, 0, "RUN_INFO", "no RUN_INFO of the run in the log");
  if (frames.empty()) throw InputError(path, 0, "SIM_FRAME", "no SIM_FRAME of the run in the log");
  if (!(info->haptic_rate_hz > 0.0))
    throw InputError(path, 0, "RUN_INFO", "the run's haptic rate is not positive");
  run.info = std::move(*info);
  run.timeline = std::make_unique<RunTimeline>(1.0 / run.info.haptic_rate_hz);
  for (const auto& msg : frames) run.timeline->Add(msg);
  for (const auto& msg : haptic) run.timeline->Add(msg);
  for (const auto& msg : devices) run.timeline->Add(msg);
  return run;
}

}  // namespace hapsim::view
