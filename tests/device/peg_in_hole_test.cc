// scenes/peg_in_hole.yaml (rigid only: no FEM is built) in the constraint-based modes (reference,
// linear) and the penalty mode of paper 000, each against the statics of the scene: the peg, 2 mm
// short of where the device is held under the hole's floor, rests on the floor with
//   constraint: the device force k_c D (the floor stops the peg at its surface);
//   penalty:    the peg sinks by d = (k_c D + m g)/(k + k_c), the device feels k_c (D − d)
// (springs in series: the paper's 0.6 N/mm is soft beside the 1 N/mm coupling).
// And the peg went into the hole: its bottom below the board's top, centred within the clearance.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "config/scene.h"
#include "config/simulation_builder.h"
#include "device/multirate_simulator.h"
#include "tests/device/simulate_scene.h"

namespace hapsim::device {
namespace {

constexpr double kFloorTop_m = -0.015;  // the hole's floor
constexpr double kPegHalfLength_m = 0.015;
constexpr double kDeviceBelow_m = 0.002;  // the device, under the peg resting on the floor

TEST(PegInHole, RigidSceneBuildsNoFem) {
  const config::Scene scene = config::LoadScene("scenes/peg_in_hole.yaml");
  EXPECT_FALSE(scene.body.has_value());
  EXPECT_EQ(scene.rigid_objects.size(), 5u);
}

TEST(PegInHole, PegRestsOnTheFloorWithTheStaticForceOfEachMode) {
  const config::Scene scene = config::LoadScene("scenes/peg_in_hole.yaml");
  ASSERT_TRUE(scene.tool);
  const double k_c = scene.coupling.k_lin_N_m;
  const double weight_N = scene.tool->model.mass_kg * 9.81;
  const double k = scene.haptic.geometric.penalty.stiffness_N_m;
  const double sink_m = (k_c * kDeviceBelow_m + weight_N) / (k + k_c);
  struct Expected {
    HapticMode mode;
    double sink_m;
    double device_force_N;
  };
  for (const Expected& e :
       {Expected{HapticMode::kReference, 0.0, k_c * kDeviceBelow_m},
        Expected{HapticMode::kLinear, 0.0, k_c * kDeviceBelow_m},
        Expected{HapticMode::kPenalty, sink_m, k_c * (kDeviceBelow_m - sink_m)}}) {
    const std::vector<HapticSample> run = SimulateScene(scene, e.mode);
    // Held still on the floor from 2.4 to 3.0 s: at 2.9 s, settled.
    const HapticSample& rest = run[2900];
    ASSERT_NEAR(rest.t_s, 2.9, 1e-9);
    const double bottom_m = rest.tool_x_W_m.z() - kPegHalfLength_m;
    EXPECT_NEAR(bottom_m, kFloorTop_m - e.sink_m, 2e-5) << ToString(e.mode);
    EXPECT_NEAR(rest.device_force_W_N.z(), e.device_force_N, 0.01) << ToString(e.mode);
    // In the hole: centred within its 0.5 mm clearance.
    EXPECT_LT(rest.tool_x_W_m.head<2>().norm(), 5e-4) << ToString(e.mode);
  }
}

}  // namespace
}  // namespace hapsim::device
