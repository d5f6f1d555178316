#include "view/live_run.h"

#include <chrono>
#include <limits>
#include <thread>

#include "core/realtime.h"
#include "messages/channels.h"
#include "messages/receive_thread.h"
#include "messages/wire_decode.h"

namespace hapsim::view {

LiveRun::LiveRun(lcm::LCM* lcm, std::int64_t run_id, const char* process) : gate_(process, run_id) {
  messages::KeepQueued(lcm->subscribe(messages::kRunInfoChannel, &LiveRun::OnRunInfo, this));
  messages::KeepQueued(lcm->subscribe(messages::kSimFrameChannel, &LiveRun::OnFrame, this));
  messages::KeepQueued(
      lcm->subscribe(messages::kHapticStateChannel, &LiveRun::OnHapticState, this));
  messages::KeepQueued(
      lcm->subscribe(messages::kDeviceStateChannel, &LiveRun::OnDeviceState, this));
}

void LiveRun::OnRunInfo(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  hapsim_lcm::run_info_t msg;
  std::string error;
  // Without a run id the first RUN_INFO that decodes names the run.
  if (gate_.run_id() == 0 &&
      messages::Decode(buffer->data, static_cast<int>(buffer->data_size), &msg, &error) &&
      msg.haptic_rate_hz > 0.0)
    gate_.AdoptRun(msg.run_id);
  if (!gate_.Admit(buffer, channel, &msg)) return;
  if (!(msg.haptic_rate_hz > 0.0)) {
    gate_.CountRejected(channel, "haptic_rate_hz is not positive");
    return;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (info_) return;  // RUN_INFO is repeated every second; the first one serves
  info_ = msg;
  timeline_ = std::make_unique<RunTimeline>(1.0 / msg.haptic_rate_hz);
}

void LiveRun::OnFrame(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  hapsim_lcm::sim_frame_t msg;
  if (!gate_.Admit(buffer, channel, &msg) || !timeline_) return;
  std::string error;
  if (!IsDrawableFrame(msg, &error)) {
    gate_.CountRejected(channel, error);
    return;
  }
  timeline_->Add(msg);
  last_message_ns_.store(MonotonicNs());
}

void LiveRun::OnHapticState(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  hapsim_lcm::haptic_state_t msg;
  if (!gate_.Admit(buffer, channel, &msg) || !timeline_) return;
  timeline_->Add(msg);
  last_message_ns_.store(MonotonicNs());
}

void LiveRun::OnDeviceState(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
  hapsim_lcm::device_state_t msg;
  if (gate_.Admit(buffer, channel, &msg) && timeline_) timeline_->Add(msg);
}

std::optional<hapsim_lcm::run_info_t> LiveRun::WaitForRunInfo(double wait_s) const {
  const std::int64_t give_up_ns = MonotonicNs() + static_cast<std::int64_t>(1e9 * wait_s);
  while (MonotonicNs() < give_up_ns && !g_stop_requested.load()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (info_) return info_;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return std::nullopt;
}

double LiveRun::SecondsSinceLastMessage() const {
  const std::int64_t last = last_message_ns_.load();
  if (last == 0) return std::numeric_limits<double>::infinity();
  return 1e-9 * static_cast<double>(MonotonicNs() - last);
}

}  // namespace hapsim::view
