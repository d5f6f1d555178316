// Tests of device/haptic_safety.h and device/passivity_observer.h: over a long random run with
// NaNs, spikes and model switches the output never exceeds the clamp nor the rate limit (except
// a drop to zero); NaN/stale device → zero at once; a stale model fades linearly to exactly
// zero; a new model's step is a linear ramp ending exactly on the new wrench; bad limits throw
// naming the field; the passivity observer against the analytic energy of a spring, a damper
// and a negative damper; neither allocates.

#include "device/haptic_safety.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "device/passivity_observer.h"
#include "tests/allocation_counter.h"

namespace hapsim::device {
namespace {

constexpr double kDt_s = 1e-3;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;
// The outputs are a few products and sums of O(10) values: rounding is ~1e-15; 1e-12 leaves
// room and is still far below anything a device could render.
constexpr double kTolerance = 1e-12;

SafetyInputs Inputs(double model_age_s, bool new_model = false, double device_age_s = 0.0,
                    bool device_finite = true) {
  SafetyInputs in;
  in.device_age_s = device_age_s;
  in.model_age_s = model_age_s;
  in.new_model = new_model;
  in.device_finite = device_finite;
  return in;
}

// Feeds a constant wrench with a fresh model until the start-up blend is over; returns the
// last output.
SafeWrench Settle(HapticSafety* safety, const Eigen::Vector3d& F, const Eigen::Vector3d& T) {
  SafeWrench out = safety->Filter(F, T, Inputs(0.0, true));
  for (int k = 0; k < 3 * safety->blend_steps(); ++k) out = safety->Filter(F, T, Inputs(0.0));
  return out;
}

void ExpectZero(const SafeWrench& out, SafetyState why) {
  EXPECT_EQ(out.force_W_N, Eigen::Vector3d::Zero());
  EXPECT_EQ(out.torque_W_N_m, Eigen::Vector3d::Zero());
  EXPECT_EQ(out.state, why) << ToString(out.state);
  EXPECT_TRUE(out.zeroed);
}

// (a) The clamp and the rate limit hold over a whole run whatever comes in.
TEST(HapticSafety, ClampAndRateHoldOverRandomRun) {
  const SafetyLimits limits;
  HapticSafety safety(limits, kDt_s);
  std::mt19937 rng(20240604);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), chance(0.0, 1.0);
  const double max_dF = limits.max_force_rate_N_s * kDt_s;
  const double max_dT = limits.max_torque_rate_N_m_s * kDt_s;
  Eigen::Vector3d last_F = Eigen::Vector3d::Zero(), last_T = Eigen::Vector3d::Zero();
  double model_age_s = kInf;
  int num_zeroed = 0, num_clamped = 0, num_limited = 0, num_fading = 0;
  for (int k = 0; k < 10000; ++k) {
    const double t = k * kDt_s;
    // A smooth wrench up to 1.2× the limits, with 10× spikes and NaN/Inf entries.
    Eigen::Vector3d F = 12.0 * Eigen::Vector3d(std::sin(7 * t), std::cos(3 * t), std::sin(t));
    Eigen::Vector3d T = 0.6 * Eigen::Vector3d(std::cos(5 * t), std::sin(2 * t), 0.5);
    if (chance(rng) < 0.02) F = 10.0 * limits.max_force_N * Eigen::Vector3d::Random();
    if (chance(rng) < 0.02) T = 10.0 * limits.max_torque_N_m * Eigen::Vector3d::Random();
    if (chance(rng) < 0.005) F[k % 3] = kNaN;
    if (chance(rng) < 0.005) T[k % 3] = -kInf;
    // Models every ~17 steps, with pauses (k in [4000, 4200): the model goes stale).
    const bool new_model = (k < 4000 || k >= 4200) && chance(rng) < 0.06;
    model_age_s = new_model ? 0.0 : model_age_s + kDt_s;
    const double device_age_s = chance(rng) < 0.01 ? 0.01 : 0.001 * chance(rng);
    const bool device_finite = chance(rng) > 0.005;
    const SafeWrench out =
        safety.Filter(F, T, Inputs(model_age_s, new_model, device_age_s, device_finite));
    ASSERT_TRUE(out.force_W_N.allFinite() && out.torque_W_N_m.allFinite()) << k;
    EXPECT_LE(out.force_W_N.norm(), limits.max_force_N + kTolerance) << k;
    EXPECT_LE(out.torque_W_N_m.norm(), limits.max_torque_N_m + kTolerance) << k;
    const bool to_zero = out.force_W_N.isZero(0.0) && out.torque_W_N_m.isZero(0.0);  // exactly zero
    if (!to_zero) {
      EXPECT_LE((out.force_W_N - last_F).norm(), max_dF + kTolerance) << k;
      EXPECT_LE((out.torque_W_N_m - last_T).norm(), max_dT + kTolerance) << k;
    }
    last_F = out.force_W_N;
    last_T = out.torque_W_N_m;
    num_zeroed += out.zeroed;
    num_clamped += out.state == SafetyState::kForceClamped;
    num_limited += out.state == SafetyState::kRateLimited;
    num_fading += out.state == SafetyState::kModelFading;
  }
  // Every rule was exercised (the run is not vacuous).
  EXPECT_GT(num_zeroed, 100);
  EXPECT_GT(num_clamped, 100);
  EXPECT_GT(num_limited, 100);
  EXPECT_GT(num_fading, 10);
}

// A finite but enormous wrench is clamped, not overflowed into Inf/NaN.
TEST(HapticSafety, HugeFiniteWrenchIsClamped) {
  HapticSafety safety(SafetyLimits{}, kDt_s);
  const Eigen::Vector3d huge = Eigen::Vector3d::Constant(1e307);
  SafeWrench out;
  for (int k = 0; k < 20; ++k) out = safety.Filter(huge, -huge, Inputs(0.0, k == 0));
  EXPECT_NEAR(out.force_W_N.norm(), 10.0, kTolerance);
  EXPECT_NEAR(out.torque_W_N_m.norm(), 0.5, kTolerance);
  EXPECT_NEAR(out.force_W_N.x(), 10.0 / std::sqrt(3.0), kTolerance);  // along the input
}

// (b) NaN in the device state or the wrench: zero at the very next output.
TEST(HapticSafety, NonFiniteGivesZeroAtOnce) {
  HapticSafety safety(SafetyLimits{}, kDt_s);
  const Eigen::Vector3d F(3, -4, 2), T(0.1, 0.2, -0.1);
  const SafeWrench steady = Settle(&safety, F, T);
  ASSERT_EQ(steady.state, SafetyState::kOk);
  ASSERT_TRUE(steady.force_W_N.isApprox(F, kTolerance));
  ExpectZero(safety.Filter(F, T, Inputs(0.0, false, 0.0, false)), SafetyState::kNonFiniteDevice);

  Settle(&safety, F, T);
  ExpectZero(safety.Filter(Eigen::Vector3d(kNaN, 0, 0), T, Inputs(0.0)),
             SafetyState::kNonFiniteWrench);
  Settle(&safety, F, T);
  ExpectZero(safety.Filter(F, Eigen::Vector3d(0, kInf, 0), Inputs(0.0)),
             SafetyState::kNonFiniteWrench);
  EXPECT_STREQ(ToString(SafetyState::kNonFiniteDevice), "device state is NaN/Inf");
}

// (c) A model that stops being refreshed fades linearly from model_stale/2 to exactly zero.
TEST(HapticSafety, StaleModelFadesToExactlyZero) {
  const SafetyLimits limits;
  HapticSafety safety(limits, kDt_s);
  const Eigen::Vector3d F(4, 0, 0), T(0, 0, 0.2);
  Settle(&safety, F, T);
  const double half_s = 0.5 * limits.model_stale_s;
  for (int k = 0; k * kDt_s < limits.model_stale_s; ++k) {
    const double age_s = k * kDt_s;
    const SafeWrench out = safety.Filter(F, T, Inputs(age_s));
    const double scale = std::min(1.0, (limits.model_stale_s - age_s) / half_s);
    EXPECT_NEAR(out.force_W_N.x(), 4.0 * scale, kTolerance) << age_s;
    EXPECT_NEAR(out.torque_W_N_m.z(), 0.2 * scale, kTolerance) << age_s;
    EXPECT_EQ(out.state, scale < 1.0 ? SafetyState::kModelFading : SafetyState::kOk) << age_s;
  }
  // Mid-fade, three quarters of the way to stale: half the force.
  HapticSafety mid(limits, kDt_s);
  Settle(&mid, F, T);
  for (double age_s = half_s; age_s < 0.75 * limits.model_stale_s; age_s += kDt_s)
    mid.Filter(F, T, Inputs(age_s));
  EXPECT_NEAR(mid.Filter(F, T, Inputs(0.075)).force_W_N.x(), 2.0, kTolerance);
  // At and beyond model_stale_s: exactly zero, and it stays so.
  ExpectZero(safety.Filter(F, T, Inputs(limits.model_stale_s)), SafetyState::kModelStale);
  for (int k = 1; k < 100; ++k)
    ExpectZero(safety.Filter(F, T, Inputs(limits.model_stale_s + k * kDt_s)),
               SafetyState::kModelStale);
  ExpectZero(safety.Filter(F, T, Inputs(kNaN)), SafetyState::kModelStale);
  ExpectZero(safety.Filter(F, T, Inputs(kInf)), SafetyState::kNoModel);
}

// (d) A device state older than device_stale_s gives zero at once.
TEST(HapticSafety, StaleDeviceGivesZeroAtOnce) {
  const SafetyLimits limits;
  HapticSafety safety(limits, kDt_s);
  const Eigen::Vector3d F(0, 0, 7), T(0.3, 0, 0);
  Settle(&safety, F, T);
  const SafeWrench at_threshold = safety.Filter(F, T, Inputs(0.0, false, limits.device_stale_s));
  EXPECT_EQ(at_threshold.state, SafetyState::kOk);  // ≤ threshold: still fresh
  EXPECT_TRUE(at_threshold.force_W_N.isApprox(F, kTolerance));
  ExpectZero(safety.Filter(F, T, Inputs(0.0, false, 1.2 * limits.device_stale_s)),
             SafetyState::kDeviceStale);
  Settle(&safety, F, T);
  ExpectZero(safety.Filter(F, T, Inputs(0.0, false, kNaN)), SafetyState::kDeviceStale);
}

// (e) A new model that steps the input by 2 N: a linear ramp, exactly on the new input after
// blend_time_s.
TEST(HapticSafety, NewModelIsBlendedNotJumped) {
  const SafetyLimits limits;
  HapticSafety safety(limits, kDt_s);
  const Eigen::Vector3d F1(1, 0.5, 0), F2(1, 2.5, 0), T(0, 0.1, 0);
  ASSERT_TRUE(Settle(&safety, F1, T).force_W_N.isApprox(F1, kTolerance));
  const int n = static_cast<int>(std::lround(limits.blend_time_s / kDt_s));  // 10 steps
  ASSERT_EQ(n, 10);
  Eigen::Vector3d last = F1;
  for (int k = 0; k <= n; ++k) {
    const SafeWrench out = safety.Filter(F2, T, Inputs(k * kDt_s, k == 0));
    EXPECT_LE((out.force_W_N - last).norm(), 2.0 / n + kTolerance) << k;  // 0.2 N a step
    EXPECT_TRUE(out.force_W_N.isApprox(F1 + (F2 - F1) * k / n, kTolerance)) << k;
    last = out.force_W_N;
  }
  EXPECT_EQ(last, F2);  // exactly, at t = blend_time_s after the switch
  EXPECT_EQ(safety.Filter(F2, T, Inputs((n + 1) * kDt_s)).force_W_N, F2);
}

// A step in the input without a new model (a spike, a steep contact) is rate limited instead.
TEST(HapticSafety, UnannouncedStepIsRateLimited) {
  const SafetyLimits limits;
  HapticSafety safety(limits, kDt_s);
  Settle(&safety, Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::Zero());
  const Eigen::Vector3d F(9, 0, 0);
  const SafeWrench first = safety.Filter(F, Eigen::Vector3d::Zero(), Inputs(0.0));
  EXPECT_EQ(first.state, SafetyState::kRateLimited);
  EXPECT_NEAR(first.force_W_N.x(), 1.0 + limits.max_force_rate_N_s * kDt_s, kTolerance);
  EXPECT_EQ(safety.Filter(F, Eigen::Vector3d::Zero(), Inputs(0.0)).force_W_N, F);
}

// The clamp keeps the direction: (15, 20, 0) N (25 N) → (6, 8, 0) N; (0, 0, 2) → (0, 0, 0.5).
TEST(HapticSafety, ClampKeepsDirection) {
  HapticSafety safety(SafetyLimits{}, kDt_s);
  const SafeWrench out = Settle(&safety, Eigen::Vector3d(15, 20, 0), Eigen::Vector3d(0, 0, 2));
  EXPECT_EQ(out.state, SafetyState::kForceClamped);
  EXPECT_TRUE(out.force_W_N.isApprox(Eigen::Vector3d(6, 8, 0), kTolerance));
  EXPECT_TRUE(out.torque_W_N_m.isApprox(Eigen::Vector3d(0, 0, 0.5), kTolerance));
}

// After a zero (or Reset) the output resumes with a blend from zero, not a jump.
TEST(HapticSafety, ResumesFromZeroWithBlend) {
  HapticSafety safety(SafetyLimits{}, kDt_s);
  const Eigen::Vector3d F(0, 4, 0);
  Settle(&safety, F, Eigen::Vector3d::Zero());
  safety.Reset();
  const int n = safety.blend_steps();
  for (int k = 0; k <= n; ++k) {
    const SafeWrench out = safety.Filter(F, Eigen::Vector3d::Zero(), Inputs(0.0));
    EXPECT_LT((out.force_W_N - F * k / n).norm(), kTolerance) << k;
  }
}

// (f) Non-positive or NaN limits throw, naming the field.
TEST(HapticSafety, RejectsBadLimitsNamingTheField) {
  const std::vector<std::pair<const char*, double SafetyLimits::*>> fields = {
      {"max_force_N", &SafetyLimits::max_force_N},
      {"max_torque_N_m", &SafetyLimits::max_torque_N_m},
      {"max_force_rate_N_s", &SafetyLimits::max_force_rate_N_s},
      {"max_torque_rate_N_m_s", &SafetyLimits::max_torque_rate_N_m_s},
      {"device_stale_s", &SafetyLimits::device_stale_s},
      {"model_stale_s", &SafetyLimits::model_stale_s},
      {"blend_time_s", &SafetyLimits::blend_time_s}};
  for (const auto& [name, field] : fields) {
    for (const double bad : {0.0, -1.0, kNaN}) {
      SafetyLimits limits;
      limits.*field = bad;
      try {
        HapticSafety safety(limits, kDt_s);
        ADD_FAILURE() << name << " = " << bad << " accepted";
      } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      }
    }
  }
  EXPECT_THROW(HapticSafety(SafetyLimits{}, 0.0), std::invalid_argument);
}

// Every state has its own text.
TEST(HapticSafety, StatesHaveText) {
  for (int s = 0; s <= static_cast<int>(SafetyState::kRateLimited); ++s)
    for (int r = 0; r < s; ++r)
      EXPECT_STRNE(ToString(static_cast<SafetyState>(s)), ToString(static_cast<SafetyState>(r)));
}

// (g) Passivity observer against analytic energies for x = A sin(ωt), v = Aω cos(ωt) over whole
// periods. With N samples per period the sums are exact: Σ sin cos = 0 and Σ cos² = N/2, so E
// matches the integrals to rounding; the 1e-3 and 1% tolerances are the brief's.
struct Motion {
  double A_m = 0.01, omega_rad_s = 2 * kPi * 2.0;  // 2 Hz: 500 samples a period
  int num_steps = 1000;                            // two whole periods
  double period_s() const { return 2 * kPi / omega_rad_s; }
  double x(int k) const { return A_m * std::sin(omega_rad_s * k * kDt_s); }
  double v(int k) const { return A_m * omega_rad_s * std::cos(omega_rad_s * k * kDt_s); }
};

TEST(PassivityObserver, SpringStoresAndReturnsEnergy) {
  const Motion m;
  const double k_N_m = 500.0;
  PassivityObserver observer;
  double max_E = 0.0;
  for (int k = 0; k < m.num_steps; ++k) {
    const Eigen::Vector3d x(m.x(k), 0, 0), v(m.v(k), 0, 0), zero = Eigen::Vector3d::Zero();
    observer.Update(-k_N_m * x, zero, v, zero, kDt_s);
    max_E = std::max(max_E, observer.energy_in_J());
  }
  const double peak_J = 0.5 * k_N_m * m.A_m * m.A_m;
  EXPECT_LT(std::abs(observer.energy_in_J()), 1e-3 * peak_J);
  EXPECT_NEAR(max_E, peak_J, 0.02 * peak_J);  // it did store ½kA² on the way (to sampling)
  EXPECT_FALSE(observer.active());
  EXPECT_EQ(observer.steps(), m.num_steps);
}

TEST(PassivityObserver, DamperDissipates) {
  const Motion m;
  const double b_N_s_m = 2.0, b_rot_N_m_s = 0.05, theta_amp_rad = 0.2;
  PassivityObserver observer;
  for (int k = 0; k < m.num_steps; ++k) {
    const Eigen::Vector3d v(0, m.v(k), 0), w(0, 0, theta_amp_rad / m.A_m * m.v(k));
    observer.Update(-b_N_s_m * v, -b_rot_N_m_s * w, v, w, kDt_s);
  }
  const double w2 = m.omega_rad_s * m.omega_rad_s, periods = m.num_steps * kDt_s / m.period_s();
  const double expected_J = periods * m.period_s() / 2 * w2 *
                            (b_N_s_m * m.A_m * m.A_m + b_rot_N_m_s * theta_amp_rad * theta_amp_rad);
  EXPECT_NEAR(observer.energy_in_J(), expected_J, 0.01 * expected_J);
  EXPECT_FALSE(observer.active());
}

TEST(PassivityObserver, NegativeDamperIsActive) {
  const Motion m;
  const double b_N_s_m = 2.0;
  PassivityObserver observer(1e-3);
  std::vector<double> energy_J;
  for (int k = 0; k < m.num_steps; ++k) {
    const Eigen::Vector3d v(m.v(k), 0, 0), zero = Eigen::Vector3d::Zero();
    observer.Update(b_N_s_m * v, zero, v, zero, kDt_s);
    energy_J.push_back(observer.energy_in_J());
  }
  const double expected_J =
      -b_N_s_m * m.A_m * m.A_m * m.omega_rad_s * m.omega_rad_s * m.num_steps * kDt_s / 2;
  EXPECT_NEAR(observer.energy_in_J(), expected_J, 0.01 * std::abs(expected_J));
  ASSERT_TRUE(observer.active());
  const long first = observer.first_active_step();
  ASSERT_GT(first, 0);
  EXPECT_LT(energy_J[first], -1e-3);
  EXPECT_GE(energy_J[first - 1], -1e-3);
}

TEST(PassivityObserver, IgnoresNonFiniteSamples) {
  PassivityObserver observer;
  const Eigen::Vector3d one(1, 0, 0), zero = Eigen::Vector3d::Zero();
  observer.Update(-one, zero, one, zero, kDt_s);  // E = 1e-3
  observer.Update(Eigen::Vector3d(kNaN, 0, 0), zero, one, zero, kDt_s);
  observer.Update(one, zero, Eigen::Vector3d(0, kInf, 0), zero, kDt_s);
  observer.Update(one, zero, one, zero, kNaN);
  EXPECT_DOUBLE_EQ(observer.energy_in_J(), 1e-3);
  EXPECT_EQ(observer.steps(), 4);
  EXPECT_EQ(observer.num_ignored(), 3);
}

// (h) Neither Filter nor Update allocates.
TEST(HapticSafety, FilterAndUpdateAllocateNothing) {
  HapticSafety safety(SafetyLimits{}, kDt_s);
  PassivityObserver observer;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  AllocationCounter counter;
  for (int k = 0; k < 1000; ++k) {
    const double t = k * kDt_s;
    Eigen::Vector3d F(20 * std::sin(9 * t), 3.0, 0.0), T(0.0, 0.0, std::cos(t));
    if (k % 97 == 0) F.x() = kNaN;
    const SafeWrench out =
        safety.Filter(F, T, Inputs((k % 150) * kDt_s, k % 150 == 0, 0.0, k % 211 != 0));
    observer.Update(out.force_W_N, out.torque_W_N_m, Eigen::Vector3d(std::cos(t), 0, 0),
                    Eigen::Vector3d::Zero(), kDt_s);
    sum += out.force_W_N;
  }
  const std::int64_t allocations = counter.count();
  EXPECT_TRUE(sum.allFinite());
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations not counted (sanitizer build)";
  EXPECT_EQ(allocations, 0);
}

}  // namespace
}  // namespace hapsim::device
