// hapsim_example_driver: a minimal external device driver for `hapsim haptic --device external`
// (protocol: docs/DEVICE.md). It stands in for a real device's SDK: every millisecond it reads
// the "device" (here a simulated hand pulled along the scene's scripted trajectory, so the loop
// is closed) and publishes DEVICE_STATE, and it applies the newest DEVICE_FORCE it received.
// Replace ReadHandle() and ApplyWrench() with the SDK's calls. It serves one run: --run-id, or
// the run of the first haptic process it hears announce itself (docs/DEVICE.md).
//
//   hapsim_example_driver SCENE [--lcm-url URL] [--run-id ID] [--duration S] [--wait-for-loop S]

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>

#include "config/scene.h"
#include "core/realtime.h"
#include "device/device_backend.h"
#include "messages/adapters.h"
#include "messages/channels.h"
#include "messages/message_gate.h"
#include "messages/receive_thread.h"

namespace {

class Driver {
 public:
  Driver(const hapsim::config::Scene& scene, double dt_s, std::int64_t run_id)
      : hand_(hapsim::ScriptedTrajectory(scene.trajectory), scene.hand, dt_s),
        gate_("hapsim_example_driver", run_id) {}

  // SDK: read the handle's pose and velocity (world frame, SI units).
  hapsim::DeviceState ReadHandle(double t_s) {
    double age_s;
    long sequence;
    return hand_.Read(t_s, &age_s, &sequence);
  }
  // SDK: command the wrench to the motors. A real driver also clamps to its own limits here. No
  // DEVICE_FORCE for kStaleForce_s (the haptic process is gone, and its safety layer with it):
  // zero.
  void ApplyWrench() {
    const bool fresh =
        1e-9 * static_cast<double>(hapsim::MonotonicNs() - received_ns_) <= kStaleForce_s;
    if (fresh) {
      hand_.Write(force_W_N_, torque_W_N_m_);
    } else {
      hand_.Write(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    }
  }

  // The haptic loop runs once a HAPTIC_STATE with step ≥ 0 arrives (−1: it waits for a model).
  // Without --run-id, the first haptic process heard names the run to serve.
  void OnHapticState(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    hapsim_lcm::haptic_state_t msg;
    std::string error;
    if (gate_.run_id() == 0 &&
        hapsim::messages::Decode(buffer->data, static_cast<int>(buffer->data_size), &msg, &error)) {
      gate_.AdoptRun(msg.run_id);
      std::printf("hapsim_example_driver: serving run %s\n",
                  hapsim::messages::FormatRunId(msg.run_id).c_str());
      std::fflush(stdout);
    }
    if (!gate_.Admit(buffer, channel, &msg)) return;
    if (msg.step >= 0) loop_running_ = true;
  }
  bool loop_running() const { return loop_running_; }
  std::int64_t run_id() const { return gate_.run_id(); }  // 0 until known

  void OnForce(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    hapsim_lcm::device_force_t msg;
    if (!gate_.Admit(buffer, channel, &msg)) return;
    std::string error;
    if (!hapsim::messages::FromMessage(msg, &force_W_N_, &torque_W_N_m_, &error)) {
      force_W_N_.setZero();  // never apply a wrench that failed validation
      torque_W_N_m_.setZero();
    }
    received_ns_ = hapsim::MonotonicNs();
  }

 private:
  static constexpr double kStaleForce_s = 0.003;
  hapsim::device::SimulatedHand hand_;
  std::int64_t received_ns_ = 0;  // when the last DEVICE_FORCE arrived (0: never: zero force)
  bool loop_running_ = false;
  hapsim::messages::MessageGate gate_;
  Eigen::Vector3d force_W_N_ = Eigen::Vector3d::Zero(), torque_W_N_m_ = Eigen::Vector3d::Zero();
};

// Publishes DEVICE_STATE once per period on absolute deadlines; `sequence` is +1 per sample.
class StatePublisher {
 public:
  StatePublisher(lcm::LCM* lcm, double dt_s)
      : lcm_(lcm), dt_ns_(std::llround(1e9 * dt_s)), deadline_ns_(hapsim::MonotonicNs()) {}
  // Publishes `state` for run `run_id` (nothing while it is 0, not known yet), then sleeps until
  // the next period starts.
  void PublishAndWait(const hapsim::DeviceState& state, std::int64_t run_id) {
    if (run_id != 0) {
      hapsim_lcm::device_state_t msg =
          hapsim::messages::ToMessage(state, hapsim::WallMicros(), sequence_++);
      msg.run_id = run_id;
      lcm_->publish(hapsim::messages::kDeviceStateChannel, &msg);
    }
    deadline_ns_ += dt_ns_;
    hapsim::SleepUntil(deadline_ns_);
  }

 private:
  lcm::LCM* lcm_;
  std::int64_t dt_ns_, deadline_ns_;
  long sequence_ = 0;  // waiting samples included (docs/DEVICE.md)
};

// The script stands for a hand that moves once the simulation runs: until the haptic loop has
// started (the visual process builds its body, then waits for a device state, and the haptic
// process for the first model) the handle is held at the script's start, so that the script's
// clock and the loop's start together, as with an in-process device. A real device has no
// script: its driver just publishes what it reads. Throws after wait_s.
void HoldUntilLoopRuns(lcm::LCM* lcm, Driver* driver, StatePublisher* publisher, double wait_s,
                       const std::string& url) {
  const std::int64_t give_up_ns = hapsim::MonotonicNs() + std::llround(1e9 * wait_s);
  const hapsim::DeviceState start = driver->ReadHandle(0.0);
  while (!driver->loop_running() && !hapsim::g_stop_requested.load()) {
    if (hapsim::MonotonicNs() > give_up_ns)
      throw std::runtime_error("no haptic loop on " + url + " within " + std::to_string(wait_s) +
                               " s (is `hapsim run` running?)");
    while (lcm->handleTimeout(0) > 0) {
    }
    publisher->PublishAndWait(start, driver->run_id());
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Example external device driver for `hapsim haptic --device external`."};
  std::string scene_path, url = hapsim::messages::kDefaultLcmUrl;
  double duration_s = 0.0;
  app.add_option("scene", scene_path, "Scene file: its device trajectory and device.hand")
      ->required();
  app.add_option("--lcm-url", url, "LCM provider URL")->capture_default_str();
  app.add_option("--duration", duration_s, "Seconds (default: the scene's script)");
  std::string run_id_text;
  app.add_option("--run-id", run_id_text,
                 "The run to serve (as `hapsim run` prints it); default: the first haptic\n"
                 "process heard on the URL");
  double wait_s = 30.0;
  app.add_option("--wait-for-loop", wait_s,
                 "Seconds to hold the handle at the script's start waiting for the haptic loop")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const hapsim::config::Scene scene = hapsim::config::LoadScene(scene_path);
    const double dt_s = 1.0 / scene.haptic.rate_hz;
    const long steps =
        std::lround((duration_s > 0.0 ? duration_s : scene.num_steps * scene.dt_s) / dt_s);
    lcm::LCM lcm(url);
    if (!lcm.good()) throw std::runtime_error("LCM: cannot open " + url);
    std::int64_t run_id = 0;
    if (!run_id_text.empty() && !hapsim::messages::ParseRunId(run_id_text, &run_id))
      throw std::runtime_error("--run-id: not 1-16 hex digits (and not 0): " + run_id_text);
    Driver driver(scene, dt_s, run_id);
    // LCM refuses the newest message once 30 wait (messages/receive_thread.h): after a stall the
    // driver would apply old forces. Drained every millisecond below, so the queue stays short.
    hapsim::messages::KeepQueued(
        lcm.subscribe(hapsim::messages::kDeviceForceChannel, &Driver::OnForce, &driver));
    hapsim::messages::KeepQueued(
        lcm.subscribe(hapsim::messages::kHapticStateChannel, &Driver::OnHapticState, &driver));
    hapsim::InstallStopHandlers();
    // A device's loop is as time-critical as the haptic loop: real-time when permitted.
    const std::string rt_failure = hapsim::RequestRealtime(80);
    if (!rt_failure.empty())
      std::fprintf(stderr, "hapsim_example_driver: warning: normal scheduling (%s)\n",
                   rt_failure.c_str());
    StatePublisher publisher(&lcm, dt_s);
    HoldUntilLoopRuns(&lcm, &driver, &publisher, wait_s, url);
    for (long k = 0; k < steps && !hapsim::g_stop_requested.load(); ++k) {
      while (lcm.handleTimeout(0) > 0) {
      }  // apply the newest force first
      driver.ApplyWrench();
      publisher.PublishAndWait(driver.ReadHandle(k * dt_s), driver.run_id());
    }
  } catch (const std::exception& error) {
    std::fprintf(stderr, "hapsim_example_driver: error: %s\n", error.what());
    return 1;
  }
  return 0;
}
