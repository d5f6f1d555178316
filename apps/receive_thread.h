#pragma once
// A thread that handles an LCM instance's subscriptions until stopped (both processes of a run
// receive off their main loop). LCM allows publishing from another thread meanwhile.

#include <lcm/lcm-cpp.hpp>

#include <atomic>
#include <thread>

namespace hapsim::apps {

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

}  // namespace hapsim::apps
