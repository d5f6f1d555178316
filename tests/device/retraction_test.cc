// scenes/retraction.yaml: forceps close on a soft flap's top edge, pull it back 12 mm and let go
// (issue 28). The flap's pull between the 50 Hz visual frames is rendered from the grasp's rows
// (bilateral, held in the linear contact model and the hybrid solve), against a second method:
// the reference mode, every stage at the haptic step (1 kHz frames, exact compliance).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "config/body_builder.h"
#include "config/scene.h"
#include "tests/device/simulate_scene.h"

namespace hapsim::device {
namespace {

constexpr double kClose_s = 0.8, kRelease_s = 3.2;  // the script's button

std::vector<HapticSample> Simulate(
    HapticMode mode, contact::ModelComplianceStep step = contact::ModelComplianceStep::kAuto) {
  config::Scene scene = config::LoadScene("scenes/retraction.yaml");
  scene.contact.model_compliance_step = step;
  const config::Body body = *config::MakeSceneBody(scene);
  return SimulateScene(scene, mode, &body);
}

// The largest pull the device feels while the jaws hold the flap: its force less the free tool's
// weight-holding force before the grasp.
double PeakPull_N(const std::vector<HapticSample>& samples) {
  const Eigen::Vector3d before_N = samples[std::lround(0.2 * 1000)].device_force_W_N;
  double peak_N = 0.0;
  for (const HapticSample& s : samples)
    if (s.t_s > kClose_s && s.t_s < kRelease_s)
      peak_N = std::max(peak_N, (s.device_force_W_N - before_N).norm());
  return peak_N;
}

// The default hybrid mode, and the paper's linear model with the body compliance of the haptic
// step (with the visual step's, the paper's choice, the pull is felt 8 % RMS off: the body then
// yields within one haptic step as it would within a frame; docs/SCENES.md).
TEST(Retraction, PullBetweenFramesFollowsTheReference) {
  const std::vector<HapticSample> reference = Simulate(HapticMode::kReference);
  const double peak_N = PeakPull_N(reference);
  ASSERT_GT(peak_N, 0.2) << "the grasp must pull";
  for (const HapticMode mode : {HapticMode::kHybrid, HapticMode::kLinear}) {
    const std::vector<HapticSample> samples =
        Simulate(mode, mode == HapticMode::kLinear ? contact::ModelComplianceStep::kHaptic
                                                   : contact::ModelComplianceStep::kAuto);
    ASSERT_EQ(samples.size(), reference.size());
    double sum_sq = 0.0, worst_N = 0.0;
    for (size_t k = 0; k < samples.size(); ++k) {
      const double difference_N =
          (samples[k].device_force_W_N - reference[k].device_force_W_N).norm();
      sum_sq += difference_N * difference_N;
      worst_N = std::max(worst_N, difference_N);
    }
    const double rms_N = std::sqrt(sum_sq / static_cast<double>(samples.size()));
    std::printf(
        "%s: peak pull %.4f N (reference %.4f N); device force vs reference: RMS %.4f N, "
        "worst %.4f N\n",
        ToString(mode), PeakPull_N(samples), peak_N, rms_N, worst_N);
    EXPECT_NEAR(PeakPull_N(samples), peak_N, 0.05 * peak_N) << ToString(mode);
    EXPECT_LT(rms_N, 0.03 * peak_N) << ToString(mode);
    // The worst is the release: the reference lets go at its step, the frame at its next start.
    EXPECT_LT(worst_N, 0.5 * peak_N) << ToString(mode);
  }
}

// The button read at the first frame that starts after its release opens the jaws: from then on
// no row pulls (the two-process loop blends the step out over haptic.blend_time_s). Neither the
// grasp nor the release is a jump at 1 kHz: the device force changes by under 0.1 N a step
// (measured 0.032 N at the release) against a 0.3 N pull, where the safety layer would clip at
// max_force_rate_N_s · Δt = 5 N.
TEST(Retraction, ReleaseLetsGoAtTheNextFrameWithoutAJump) {
  const config::Scene scene = config::LoadScene("scenes/retraction.yaml");
  const std::vector<HapticSample> samples = Simulate(HapticMode::kHybrid);
  double pulled_N = 0.0, largest_step_N = 0.0;
  for (size_t k = 0; k < samples.size(); ++k) {
    const HapticSample& s = samples[k];
    if (s.t_s > kClose_s + 0.5 && s.t_s < kRelease_s)
      pulled_N = std::max(pulled_N, s.contact_force_W_N.norm());
    if (s.t_s >= kRelease_s + scene.dt_s) {
      EXPECT_EQ(s.contact_force_W_N.norm(), 0.0) << s.t_s;
    }
    if (k > 0)
      largest_step_N =
          std::max(largest_step_N, (s.device_force_W_N - samples[k - 1].device_force_W_N).norm());
  }
  std::printf("pull %.4f N; largest change of the device force in one step %.4f N\n", pulled_N,
              largest_step_N);
  EXPECT_GT(pulled_N, 0.2);
  EXPECT_LT(largest_step_N, 0.1);
}

}  // namespace
}  // namespace hapsim::device
