// The palpation scorer (view/palpation_score.h) against hand-made haptic states whose outcome is
// known: a hold inside the band for hold_s reaches a target, one step short does not; the tool's
// weight alone is no tissue force; time over the limit and the path are counted per step.
#include "view/palpation_score.h"

#include <gtest/gtest.h>

#include <Eigen/Core>

namespace hapsim::view {
namespace {

constexpr double kDt_s = 1e-3;

config::TaskScene MakeTask() {
  config::TaskScene task;
  for (const double x_m : {0.0, 0.05}) {
    config::PalpationTarget target;
    target.name = x_m == 0.0 ? "a" : "b";
    target.position_m = Eigen::Vector3d(x_m, 0.0, 0.0);
    target.radius_m = 0.005;
    task.targets.push_back(target);
  }
  task.force_band_min_N = 0.5;
  task.force_band_max_N = 2.0;
  task.hold_s = 0.1;
  task.force_limit_N = 3.0;
  task.time_limit_s = 10.0;
  return task;
}

ToolShape MakeSphere() {
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = 0.01;
  return sphere;
}

// A tool of 20 g under gravity: weight (0, 0, −0.1962) N.
const Eigen::Vector3d kWeight_N(0.0, 0.0, -0.02 * 9.81);

// The haptic state of step `step` with the tool's centre at x and a tissue force f (the device
// force is then f + m g: the coupling holds the weight and the push).
hapsim_lcm::haptic_state_t State(long step, const Eigen::Vector3d& x_W_m,
                                 const Eigen::Vector3d& tissue_force_N) {
  hapsim_lcm::haptic_state_t state{};
  state.step = step;
  for (int d = 0; d < 3; ++d) {
    state.x_W_m[d] = x_W_m[d];
    state.force_device_W_N[d] = tissue_force_N[d] + kWeight_N[d];
  }
  state.q_WT[0] = 1.0;
  return state;
}

TEST(PalpationScorer, AHoldInTheBandForHoldTimeReachesATargetAndOneStepLessDoesNot) {
  PalpationScorer scorer(MakeTask(), MakeSphere(), kWeight_N, kDt_s);
  const Eigen::Vector3d on_a(0.0, 0.0, 0.012);  // the sphere's surface 2 mm above a's centre
  const Eigen::Vector3d push_N(0.0, 0.0, -1.0);
  long step = 0;
  for (; step < 99; ++step) scorer.Add(State(step, on_a, push_N));
  EXPECT_FALSE(scorer.reached()[0]);  // 99 ms of 100
  scorer.Add(State(step++, on_a, push_N));
  EXPECT_TRUE(scorer.reached()[0]);
  EXPECT_FALSE(scorer.reached()[1]);
  EXPECT_FALSE(scorer.completed());
  EXPECT_NEAR(scorer.ToJson()["peak_force_N"].get<double>(), 1.0, 1e-12);
}

TEST(PalpationScorer, TheToolsWeightAloneIsNoTissueForce) {
  PalpationScorer scorer(MakeTask(), MakeSphere(), kWeight_N, kDt_s);
  // Resting in a target's ball with no contact: the device holds 0.196 N of weight, in a band
  // whose low end is 0.5 N here, but a heavier tool would sit in it: the tissue force is zero.
  for (long step = 0; step < 500; ++step)
    scorer.Add(State(step, Eigen::Vector3d(0.0, 0.0, 0.012), Eigen::Vector3d::Zero()));
  EXPECT_FALSE(scorer.reached()[0]);
  EXPECT_NEAR(scorer.ToJson()["peak_force_N"].get<double>(), 0.0, 1e-12);
}

TEST(PalpationScorer, CountsTimeOverTheLimitAndThePath) {
  PalpationScorer scorer(MakeTask(), MakeSphere(), kWeight_N, kDt_s);
  // 200 steps pressing with 4 N (over the 3 N limit) while sliding 10 mm along x at constant
  // speed; then 100 steps at 1 N.
  long step = 0;
  for (; step < 200; ++step)
    scorer.Add(State(step, Eigen::Vector3d(0.01 * step / 200.0, 0.0, 0.03),
                     Eigen::Vector3d(0.0, 0.0, -4.0)));
  EXPECT_TRUE(scorer.over_limit());
  for (; step < 300; ++step)
    scorer.Add(State(step, Eigen::Vector3d(0.01, 0.0, 0.03), Eigen::Vector3d(0.0, 0.0, -1.0)));
  EXPECT_FALSE(scorer.over_limit());
  const nlohmann::json summary = scorer.ToJson();
  EXPECT_NEAR(summary["time_over_force_limit_s"].get<double>(), 0.2, 1e-9);
  // Sampled every 10 steps (0, 10, …, 290): the slide's 10 mm, the last sample of it at step 200.
  EXPECT_NEAR(summary["tool_path_length_m"].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(summary["peak_force_N"].get<double>(), 4.0, 1e-12);
}

// A retraction task: the same targets, with the jaws' tissue counted from the frames. Each frame
// counts once, however often it is fed (the trainer feeds what came since its last).
TEST(PalpationScorer, AGrasperCountsThePointsThatSlippedOncePerFrame) {
  PalpationScorer scorer(MakeTask(), MakeSphere(), kWeight_N, kDt_s, /*grasper=*/true);
  scorer.AddFrame(0, 5, 0);
  scorer.AddFrame(1, 3, 2);
  scorer.AddFrame(1, 3, 2);  // the same frame again
  scorer.AddFrame(0, 5, 0);  // an older one
  EXPECT_EQ(scorer.points_slipped(), 2);
  EXPECT_NE(scorer.StatusLine().find("holding 3 points   TORN: 2 slipped"), std::string::npos)
      << scorer.StatusLine();
  scorer.AddFrame(2, 0, 3);
  const nlohmann::json summary = scorer.ToJson();
  EXPECT_EQ(summary["grip_slipped_points"].get<int>(), 5);
  EXPECT_TRUE(summary["tissue_torn"].get<bool>());
  // A tool without jaws: no grasp in the score.
  PalpationScorer probe(MakeTask(), MakeSphere(), kWeight_N, kDt_s);
  EXPECT_FALSE(probe.ToJson().contains("tissue_torn"));
  EXPECT_EQ(probe.StatusLine().find("holding"), std::string::npos);
}

}  // namespace
}  // namespace hapsim::view
