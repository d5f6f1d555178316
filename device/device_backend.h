#pragma once
// Where the haptic loop gets the device state and sends the device wrench (issue 4). Backends:
//   ScriptedDevice   the scene's waypoint trajectory; ignores the wrench (open loop)
//   SimulatedHand    a mass–spring–damper hand holding the handle and pulled along the scripted
//                    trajectory: the wrench acts back on it, so the loop is closed and stability
//                    can be tested without hardware
//   (ExternalDevice in apps/haptic_command.cc: an external driver process over LCM)
// Called from the 1 kHz loop: Read and Write must not block or allocate.

#include <Eigen/Core>

#include "core/virtual_coupling.h"
#include "core/scripted_trajectory.h"

namespace hapsim::device {

class DeviceBackend {
 public:
  virtual ~DeviceBackend() = default;
  // The device state for the haptic step at time t_s; *age_s how long ago it was measured and
  // *sequence its sample number (for logs and replay).
  virtual DeviceState Read(double t_s, double* age_s, long* sequence) = 0;
  // The wrench to apply to the handle this step (world, N and N m).
  virtual void Write(const Eigen::Vector3d& force_W_N, const Eigen::Vector3d& torque_W_N_m) = 0;
};

class ScriptedDevice : public DeviceBackend {
 public:
  explicit ScriptedDevice(ScriptedTrajectory script) : script_(std::move(script)) {}
  DeviceState Read(double t_s, double* age_s, long* sequence) override;
  void Write(const Eigen::Vector3d&, const Eigen::Vector3d&) override {}

 private:
  ScriptedTrajectory script_;
  long count_ = 0;
};

struct HandParams {
  double mass_kg = 0.3;      // hand and handle, moving together
  double k_N_m = 300.0;      // arm stiffness pulling the hand to the scripted target
  double b_N_s_m = 10.0;     // arm damping
};

// The handle's translation follows m ẍ = k (x_target − x) + b (ẋ_target − ẋ) + F_device, with
// semi-implicit (symplectic) Euler at the haptic step: stable for Δt² k/m ≪ 1 and energy-
// consistent, so an active (energy-generating) virtual environment shows up as growing motion.
// The orientation follows the script (the hand holds the handle's rotation rigidly).
class SimulatedHand : public DeviceBackend {
 public:
  // Throws std::invalid_argument for non-positive mass or negative k, b, or dt_s ≤ 0.
  SimulatedHand(ScriptedTrajectory script, const HandParams& params, double dt_s);
  DeviceState Read(double t_s, double* age_s, long* sequence) override;
  void Write(const Eigen::Vector3d& force_W_N, const Eigen::Vector3d& torque_W_N_m) override;

 private:
  ScriptedTrajectory script_;
  HandParams params_;
  double dt_s_;
  bool started_ = false;
  Eigen::Vector3d x_W_m_ = Eigen::Vector3d::Zero(), v_W_m_s_ = Eigen::Vector3d::Zero();
  DeviceState target_;
  long count_ = 0;
};

}  // namespace hapsim::device
