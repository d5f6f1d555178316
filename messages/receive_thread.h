#pragma once
// A thread that handles an LCM instance's subscriptions until stopped (both processes of a run
// receive off their main loop). LCM allows publishing from another thread meanwhile.

#include <atomic>
#include <lcm/lcm-cpp.hpp>
#include <thread>

namespace hapsim::messages {

// LCM drops a message for a subscription once 30 (its default queue capacity) are waiting to be
// dispatched. A receive thread held off the CPU for 15 ms therefore lost 2 kHz traffic (the log's
// ".*" sees DEVICE_STATE and HAPTIC_STATE) in user space, with the kernel counting no UDP drop:
// the lost datagrams of loaded CI runs. 10,000 messages is 5 s of that traffic; every
// subscription a ReceiveThread dispatches goes through this (two_process_test.sh, check 7).
constexpr int kReceiveQueueCapacity = 10000;
inline lcm::Subscription* KeepQueued(lcm::Subscription* subscription) {
  subscription->setQueueCapacity(kReceiveQueueCapacity);
  return subscription;
}

// Handles LCM until stopped; stops and joins on destruction too (an exception in the loop must
// not leave a joinable thread behind, which would terminate the process).
class ReceiveThread {
 public:
  explicit ReceiveThread(lcm::LCM* lcm)
      : thread_([this, lcm] {
          while (running_.load()) lcm->handleTimeout(10);
        }) {}
  ~ReceiveThread() { Stop(); }
  void Stop() {
    running_.store(false);
    if (thread_.joinable()) thread_.join();
  }

 private:
  std::atomic<bool> running_{true};
  std::thread thread_;
};

}  // namespace hapsim::messages
