#pragma once
// The safety layer between the haptic step's rendered wrench and the device (DESIGN.md §5,
// issue 4): whatever the step, the model or the device do, what goes to the device is finite,
// within the device's force and torque limits, and changes no faster than its rate limits; on
// anything unexpected it is zero, and the state says why.
//
// Filter, once per haptic step (period dt), in this order:
//   1 device state not finite → zero at once (kNonFiniteDevice). The step's output was computed
//     from garbage (or skipped); nothing it says can be trusted.
//   2 wrench not finite → zero at once (kNonFiniteWrench). A NaN would otherwise pass through
//     every comparison below (NaN > limit is false) straight to the motors.
//   3 device state older than device_stale_s (or its age is NaN) → zero at once (kDeviceStale).
//     The force was rendered for where the hand was, not where it is: pushing on a stale pose
//     is how a haptic loop goes unstable.
//   4 no model yet (model age +∞) → zero (kNoModel); model age ≥ model_stale_s (or NaN) → zero
//     (kModelStale). The visual process has stopped: its contact model no longer describes the
//     body.
//   Zero is always safe, so 1–4 are not rate limited: the output drops to exactly zero at the
//   step they trigger (a drop of up to max_force_N at once, which a device's limits allow).
//   5 model fading: the wrench is scaled by clamp((model_stale − age)/(model_stale/2), 0, 1),
//     so a model that stops being refreshed fades linearly from model_stale/2 to zero at
//     model_stale instead of vanishing at once (kModelFading). A negative age counts as 0.
//   6 blend: when a new model arrives (or the output resumes after a zero of 1–4, or after
//     Reset), the offset between the last output sent and this step's (faded) wrench is
//     remembered and offset·(1 − k/n) is added at the k-th step after it, n = ⌈blend_time/dt⌉:
//     a model switch that steps the force becomes a linear ramp that ends exactly on the new
//     wrench n steps (≈ blend_time) later. Without it each new 60 Hz model would be felt as a
//     click; the ramp is counted in whole steps so it ends exactly.
//   7 rate limit: |ΔF| ≤ max_force_rate·dt and |ΔT| ≤ max_torque_rate·dt with respect to the
//     last output sent, by shortening the difference vector (kRateLimited). The last guard
//     against a jump the blend did not cover (a spike in the rendered wrench, a steep contact).
//   8 magnitude clamp: |F| ≤ max_force_N and |T| ≤ max_torque_N_m, scaled along the vector's
//     own direction (kForceClamped; torque too). Last, so the clamp holds whatever happened
//     before. The clamp is the projection onto a ball containing the previous output, which
//     cannot lengthen a step, so the rate limit of 7 still holds after it.
// The state reported is the first of 1–4 that zeroed the output, else the last of 5, 7, 8 that
// changed it, else kOk. The blend is normal operation and has no state of its own.
//
// Filter allocates nothing and throws nothing: it runs inside the 1 kHz loop.

#include <Eigen/Core>
#include <cstdint>

namespace hapsim::device {

// The device's limits and the staleness thresholds (scene: haptic.safety).
struct SafetyLimits {
  double max_force_N = 10.0;             // |F| ≤ this, N (clamped along its direction)
  double max_torque_N_m = 0.5;           // |T| ≤ this, N m
  double max_force_rate_N_s = 5000.0;    // |F_k − F_{k−1}| ≤ this·Δt, N/s
  double max_torque_rate_N_m_s = 250.0;  // |T_k − T_{k−1}| ≤ this·Δt, N m/s
  double device_stale_s = 0.005;         // device state older than this → zero at once, s
  double model_stale_s = 0.1;  // model older than this → zero; fades from model_stale_s/2, s
  double blend_time_s = 0.01;  // a new model's step in force is blended out over this, s
};

enum class SafetyState : std::uint8_t {
  kOk,
  kNoModel,          // no contact model has arrived yet: zero
  kModelFading,      // model older than model_stale_s/2: scaled down
  kModelStale,       // model older than model_stale_s: zero
  kDeviceStale,      // device state older than device_stale_s: zero
  kNonFiniteDevice,  // device state has a NaN/Inf: zero
  kNonFiniteWrench,  // the rendered wrench has a NaN/Inf: zero
  kForceClamped,     // |F| or |T| was above its limit: clamped
  kRateLimited,      // |ΔF| or |ΔT| was above its rate limit: limited
};

// Short human text for logs, e.g. "device state is NaN/Inf".
const char* ToString(SafetyState state);

// What Filter needs to know about this step besides the wrench.
struct SafetyInputs {
  double device_age_s = 0.0;  // time since the device state was read/received, s
  double model_age_s = 0.0;   // time since the current model arrived, s (+∞: none yet)
  bool new_model = false;     // the model changed at this step (start a blend)
  bool device_finite = true;  // every entry of the device state is finite
};

// What may be sent to the device (world frame, acting on the user's hand).
struct SafeWrench {
  Eigen::Vector3d force_W_N = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_W_N_m = Eigen::Vector3d::Zero();
  SafetyState state = SafetyState::kNoModel;
  bool zeroed = true;  // set to zero by rules 1–4 (the reason is in state)
};

class HapticSafety {
 public:
  // Throws std::invalid_argument, naming the field, if a limit or dt_s is not finite and > 0.
  HapticSafety(const SafetyLimits& limits, double dt_s);

  // Takes the wrench the haptic step rendered for the device this step (world; N, N m) and
  // returns what may be sent. Call once per step of dt_s; the order is in the file comment.
  SafeWrench Filter(const Eigen::Vector3d& force_W_N, const Eigen::Vector3d& torque_W_N_m,
                    const SafetyInputs& in) noexcept;

  // Back to zero output (e.g. after the device reconnects); the next output blends in from zero.
  void Reset() noexcept;

  const SafetyLimits& limits() const { return limits_; }
  double dt_s() const { return dt_s_; }
  // Steps a blend lasts: n = ⌈blend_time_s/dt_s⌉ (≥ 1).
  int blend_steps() const { return blend_steps_; }

 private:
  SafeWrench Zero(SafetyState why) noexcept;
  // Step 6: starts a blend if asked and adds the current offset to *force, *torque.
  void Blend(bool start, Eigen::Vector3d* force, Eigen::Vector3d* torque) noexcept;

  SafetyLimits limits_;
  double dt_s_;
  int blend_steps_;
  // The last output sent (zero after a zeroing or Reset).
  Eigen::Vector3d last_force_W_N_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d last_torque_W_N_m_ = Eigen::Vector3d::Zero();
  // The blend in progress: offsets at its start and the steps since (blend_step_ ≥ blend_steps_:
  // none).
  Eigen::Vector3d blend_force_W_N_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d blend_torque_W_N_m_ = Eigen::Vector3d::Zero();
  int blend_step_ = 0;
  bool resume_blend_ = true;  // the output was zeroed: blend in from zero when it resumes
};

}  // namespace hapsim::device
