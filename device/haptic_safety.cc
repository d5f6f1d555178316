#include "device/haptic_safety.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace hapsim::device {
namespace {

// Rounding slack for n = ⌈blend_time/dt⌉, so that 0.01/0.001 gives 10 and not 11 when the
// quotient comes out as 10.000000000000002.
constexpr double kStepRoundingTolerance = 1e-9;
// More blend steps than this cannot be counted in an int (and make no sense at 1 kHz).
constexpr double kMaxBlendSteps = 1e9;

void CheckPositive(const char* name, double value) {
  if (!(std::isfinite(value) && value > 0.0))
    throw std::invalid_argument(std::string("haptic safety: ") + name + " = " +
                                std::to_string(value) + "; it must be finite and > 0");
}

// Euclidean norm that neither overflows nor underflows (a finite 1e300 wrench must still be
// clamped, not turned into Inf/NaN by squaring). Fixed size: no allocation.
double Norm(const Eigen::Vector3d& v) { return v.stableNorm(); }

// Moves *value from `last` toward it by at most max_step (along the difference vector).
// Returns whether it was limited.
bool LimitStep(const Eigen::Vector3d& last, double max_step, Eigen::Vector3d* value) {
  const Eigen::Vector3d step = *value - last;
  const double length = Norm(step);
  if (!(length > max_step)) return false;
  *value = last + step * (max_step / length);
  return true;
}

// Scales *value along its direction to length ≤ max_length. Returns whether it was clamped.
bool ClampLength(double max_length, Eigen::Vector3d* value) {
  const double length = Norm(*value);
  if (!(length > max_length)) return false;
  *value *= max_length / length;
  return true;
}

}  // namespace

const char* ToString(SafetyState state) {
  switch (state) {
    case SafetyState::kOk:
      return "ok";
    case SafetyState::kNoModel:
      return "no contact model yet";
    case SafetyState::kModelFading:
      return "contact model is getting old: force fading";
    case SafetyState::kModelStale:
      return "contact model is stale";
    case SafetyState::kDeviceStale:
      return "device state is stale";
    case SafetyState::kNonFiniteDevice:
      return "device state is NaN/Inf";
    case SafetyState::kNonFiniteWrench:
      return "rendered wrench is NaN/Inf";
    case SafetyState::kForceClamped:
      return "force or torque clamped to the device limit";
    case SafetyState::kRateLimited:
      return "force or torque rate limited";
  }
  return "unknown safety state";
}

HapticSafety::HapticSafety(const SafetyLimits& limits, double dt_s)
    : limits_(limits), dt_s_(dt_s), blend_steps_(1) {
  CheckPositive("max_force_N", limits.max_force_N);
  CheckPositive("max_torque_N_m", limits.max_torque_N_m);
  CheckPositive("max_force_rate_N_s", limits.max_force_rate_N_s);
  CheckPositive("max_torque_rate_N_m_s", limits.max_torque_rate_N_m_s);
  CheckPositive("device_stale_s", limits.device_stale_s);
  CheckPositive("model_stale_s", limits.model_stale_s);
  CheckPositive("blend_time_s", limits.blend_time_s);
  CheckPositive("dt_s", dt_s);
  const double steps = limits.blend_time_s / dt_s;
  if (!(steps <= kMaxBlendSteps))
    throw std::invalid_argument("haptic safety: blend_time_s / dt_s = " + std::to_string(steps) +
                                " steps; it must be at most 1e9");
  blend_steps_ = std::max(1, static_cast<int>(std::ceil(steps * (1.0 - kStepRoundingTolerance))));
  blend_step_ = blend_steps_;  // no blend in progress
}

void HapticSafety::Reset() noexcept {
  last_force_W_N_.setZero();
  last_torque_W_N_m_.setZero();
  blend_step_ = blend_steps_;
  resume_blend_ = true;
}

SafeWrench HapticSafety::Zero(SafetyState why) noexcept {
  Reset();  // zero is sent; any blend in progress no longer applies
  SafeWrench out;
  out.state = why;
  out.zeroed = true;
  return out;
}

void HapticSafety::Blend(bool start, Eigen::Vector3d* force, Eigen::Vector3d* torque) noexcept {
  if (start) {
    blend_force_W_N_ = last_force_W_N_ - *force;
    blend_torque_W_N_m_ = last_torque_W_N_m_ - *torque;
    blend_step_ = 0;
  }
  if (blend_step_ >= blend_steps_) return;
  // k/n is exactly 1 at k = n: the blend ends exactly on the input.
  const double weight = 1.0 - static_cast<double>(blend_step_) / blend_steps_;
  *force += weight * blend_force_W_N_;
  *torque += weight * blend_torque_W_N_m_;
  ++blend_step_;
}

SafeWrench HapticSafety::Filter(const Eigen::Vector3d& force_W_N,
                                const Eigen::Vector3d& torque_W_N_m,
                                const SafetyInputs& in) noexcept {
  // 1–4: zero at once (comparisons are written so that a NaN age counts as stale).
  if (!in.device_finite) return Zero(SafetyState::kNonFiniteDevice);
  if (!force_W_N.allFinite() || !torque_W_N_m.allFinite())
    return Zero(SafetyState::kNonFiniteWrench);
  if (!(in.device_age_s <= limits_.device_stale_s)) return Zero(SafetyState::kDeviceStale);
  if (in.model_age_s == std::numeric_limits<double>::infinity()) return Zero(SafetyState::kNoModel);
  if (!(in.model_age_s < limits_.model_stale_s)) return Zero(SafetyState::kModelStale);

  SafeWrench out;
  out.state = SafetyState::kOk;
  out.zeroed = false;
  // 5: fade from model_stale/2 (scale 1) to model_stale (scale 0).
  const double half_stale_s = 0.5 * limits_.model_stale_s;
  const double scale =
      std::clamp((limits_.model_stale_s - in.model_age_s) / half_stale_s, 0.0, 1.0);
  out.force_W_N = scale * force_W_N;
  out.torque_W_N_m = scale * torque_W_N_m;
  if (scale < 1.0) out.state = SafetyState::kModelFading;
  // 6: blend a new model's (or a resumed output's) step into a ramp.
  Blend(in.new_model || resume_blend_, &out.force_W_N, &out.torque_W_N_m);
  resume_blend_ = false;
  // 7: rate limit with respect to the last output sent.
  const bool force_limited =
      LimitStep(last_force_W_N_, limits_.max_force_rate_N_s * dt_s_, &out.force_W_N);
  const bool torque_limited =
      LimitStep(last_torque_W_N_m_, limits_.max_torque_rate_N_m_s * dt_s_, &out.torque_W_N_m);
  if (force_limited || torque_limited) out.state = SafetyState::kRateLimited;
  // 8: magnitude clamp, last.
  const bool force_clamped = ClampLength(limits_.max_force_N, &out.force_W_N);
  const bool torque_clamped = ClampLength(limits_.max_torque_N_m, &out.torque_W_N_m);
  if (force_clamped || torque_clamped) out.state = SafetyState::kForceClamped;
  // Cannot happen with finite inputs and limits; if it does, zero is the safe answer.
  if (!out.force_W_N.allFinite() || !out.torque_W_N_m.allFinite())
    return Zero(SafetyState::kNonFiniteWrench);
  last_force_W_N_ = out.force_W_N;
  last_torque_W_N_m_ = out.torque_W_N_m;
  return out;
}

}  // namespace hapsim::device
