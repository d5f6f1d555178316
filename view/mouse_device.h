#pragma once
// `hapsim train`'s mouse as a device: the trainee's hand on the handle, published as an external
// device driver would (DEVICE_STATE over LCM, docs/DEVICE.md).

#include <Eigen/Core>
#include <atomic>
#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <thread>

namespace hapsim::view {

// The handle driven by the mouse: the window sets a target, a 1 kHz thread publishes DEVICE_STATE
// (the external-driver protocol, docs/DEVICE.md) following it through a first-order filter of
// 20 ms and at most 0.3 m/s, so that the device moves as a hand does: smoothly, not in the
// window's 15 Hz steps, and not 6 cm in a frame when the pointer jumps (a 6.5 N coupling spike
// through the coupling's damping, seen before the limit).
class MouseDevice {
 public:
  MouseDevice(lcm::LCM* lcm, std::int64_t run_id, const Eigen::Vector3d& start_W_m, double dt_s)
      : lcm_(lcm), run_id_(run_id), dt_s_(dt_s), target_W_m_(start_W_m), x_W_m_(start_W_m) {
    thread_ = std::thread([this] { Loop(); });
  }
  ~MouseDevice() {
    running_.store(false);
    thread_.join();
  }
  void SetTarget(const Eigen::Vector3d& x_W_m, int buttons) {
    std::lock_guard<std::mutex> lock(mutex_);
    target_W_m_ = x_W_m;
    buttons_ = buttons;
  }

 private:
  void Loop();

  static constexpr double kMaxSpeed_m_s = 0.3;
  lcm::LCM* lcm_;
  std::int64_t run_id_;
  double dt_s_;
  std::mutex mutex_;
  Eigen::Vector3d target_W_m_;
  int buttons_ = 0;
  Eigen::Vector3d x_W_m_;  // the loop's filtered position
  std::atomic<bool> running_{true};
  std::thread thread_;
};

}  // namespace hapsim::view
