#pragma once
// One run heard live over LCM (`hapsim view` without a log, `hapsim train`): its RUN_INFO and its
// timeline, filled by the LCM receive thread. Messages of other runs are ignored and counted
// (messages/message_gate.h); without a run id, the first RUN_INFO heard names the run.

#include <atomic>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <optional>

#include "messages/adapters.h"
#include "messages/message_gate.h"
#include "view/run_timeline.h"

namespace hapsim::view {

class LiveRun {
 public:
  // Subscribes on `lcm` (handled by the caller's ReceiveThread). run_id 0: the first run heard.
  LiveRun(lcm::LCM* lcm, std::int64_t run_id, const char* process);

  // The run's RUN_INFO, waiting up to wait_s for it; nullopt on timeout.
  std::optional<hapsim_lcm::run_info_t> WaitForRunInfo(double wait_s) const;
  // Null until RUN_INFO has come (the haptic rate sets the timeline's step). The receive thread
  // sets it once, under the lock this takes; the timeline itself locks its own reads and writes.
  RunTimeline* timeline() {
    std::lock_guard<std::mutex> lock(mutex_);
    return timeline_.get();
  }
  // Seconds since the run's visual or haptic process was last heard: its last SIM_FRAME or
  // HAPTIC_STATE (infinity before the first). A live run is never quiet for long: its haptic
  // process publishes every step, and every 10 ms while it waits for its first model, whereas the
  // visual process's frames may be seconds apart (a sanitized build on a busy host): frames alone
  // cannot tell a slow run from an ended one. DEVICE_STATE does not count: an external device's
  // driver publishes it, and may go on after the run has ended.
  double SecondsSinceLastMessage() const;
  const messages::MessageGate& gate() const { return gate_; }

 private:
  void OnRunInfo(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void OnFrame(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void OnHapticState(const lcm::ReceiveBuffer* buffer, const std::string& channel);
  void OnDeviceState(const lcm::ReceiveBuffer* buffer, const std::string& channel);

  messages::MessageGate gate_;
  mutable std::mutex mutex_;
  std::optional<hapsim_lcm::run_info_t> info_;
  std::unique_ptr<RunTimeline> timeline_;         // set once by the receive thread, under mutex_
  std::atomic<std::int64_t> last_message_ns_{0};  // MonotonicNs(); 0: none yet
};

}  // namespace hapsim::view
