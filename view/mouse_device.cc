#include "view/mouse_device.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/realtime.h"
#include "core/virtual_coupling.h"
#include "messages/adapters.h"
#include "messages/channels.h"

namespace hapsim::view {

void MouseDevice::Loop() {
  // As time-critical as the haptic loop: a DEVICE_STATE later than the haptic process's
  // device_stale_s (5 ms) zeroes the force (seen while the window rendered, before this).
  const std::string rt_failure = RequestRealtime(70);
  if (!rt_failure.empty())
    std::fprintf(stderr, "hapsim train: warning: the device thread runs unprioritised (%s)\n",
                 rt_failure.c_str());
  constexpr double kTimeConstant_s = 0.02;
  const double alpha = dt_s_ / (kTimeConstant_s + dt_s_);
  const std::int64_t period_ns = std::llround(1e9 * dt_s_);
  std::int64_t deadline_ns = MonotonicNs();
  long sequence = 0;
  while (running_.load()) {
    Eigen::Vector3d target;
    int buttons;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      target = target_W_m_;
      buttons = buttons_;
    }
    DeviceState device;
    Eigen::Vector3d step_m = alpha * (target - x_W_m_);
    if (step_m.norm() > kMaxSpeed_m_s * dt_s_) step_m *= kMaxSpeed_m_s * dt_s_ / step_m.norm();
    device.v_W_m_s = step_m / dt_s_;
    x_W_m_ += step_m;
    device.x_W_m = x_W_m_;
    device.buttons = buttons;
    hapsim_lcm::device_state_t msg = messages::ToMessage(device, WallMicros(), sequence++);
    msg.run_id = run_id_;
    lcm_->publish(messages::kDeviceStateChannel, &msg);
    deadline_ns += period_ns;
    // Held off the CPU for more than a period: start again from now, rather than publish
    // the missed samples back to back.
    if (MonotonicNs() > deadline_ns + period_ns) deadline_ns = MonotonicNs();
    SleepUntil(deadline_ns);
  }
}

}  // namespace hapsim::view
