// The haptic modes of the source papers' other systems (device/geometric_haptic_contact.h) on a
// sphere tool over a rigid plate, each against an independent value:
//  - penalty (paper 000): the steady penetration is the force pressing the tool in over k; the
//    predictive margin ε = v Δt lowers the penetration of an impact; the force never changes by
//    more than the smoothing's limit in a step;
//  - impact (paper 001): a tool dropped on the plate rebounds to e² of its drop height;
//  - material (paper 003): Hooke's force k_max S₀ S₁ d; two identical pairs give the force of
//    one; stick–slip: the tangential force is F δ up to the stickiness, then drops (the sawtooth);
//  - each mode's haptic step allocates nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "device/geometric_haptic_contact.h"
#include "device/haptic_step.h"
#include "fem/lattice_mesher.h"
#include "tests/allocation_counter.h"

namespace hapsim::device {
namespace {

constexpr double kDt_s = 1e-3;
constexpr double kG_m_s2 = 9.81;
constexpr double kRadius_m = 0.005;
constexpr double kMass_kg = 0.02;

ToolModel MakeSphereTool() {
  ToolShape shape;
  shape.kind = ToolShape::Kind::kSphere;
  shape.radius_m = kRadius_m;
  return MakeToolModelWithMass(shape, kMass_kg);
}

// A plate whose top face is z = 0, 10 cm square; at x_offset_m along x.
contact::RigidObject MakePlate(double half_x_m = 0.05, double x_offset_m = 0.0) {
  contact::RigidObject plate;
  plate.name = "plate";
  plate.shape.kind = ToolShape::Kind::kBox;
  plate.shape.half_extents_m = Eigen::Vector3d(half_x_m, 0.05, 0.005);
  plate.X_WO.translation() = Eigen::Vector3d(x_offset_m, 0, -0.005);
  return plate;
}

ToolState At(const Eigen::Vector3d& x_W_m) {
  ToolState state;
  state.x_W_m = x_W_m;
  return state;
}

DeviceState DeviceAt(const Eigen::Vector3d& x_W_m,
                     const Eigen::Vector3d& v_W_m_s = Eigen::Vector3d::Zero()) {
  DeviceState device;
  device.x_W_m = x_W_m;
  device.v_W_m_s = v_W_m_s;
  return device;
}

CouplingParams Coupling(double k_N_m, double b_N_s_m) {
  CouplingParams c;
  c.k_lin_N_m = k_N_m;
  c.b_lin_N_s_m = b_N_s_m;
  c.k_ang_N_m_rad = 0.1;
  c.b_ang_N_m_s_rad = 1e-3;
  return c;
}

// One mode on the plate: a HapticStep whose contact is the geometric mode's.
struct Rig {
  Rig(HapticMode mode, const GeometricContactParams& params, const CouplingParams& coupling,
      const ToolState& start, std::vector<contact::RigidObject> objects = {MakePlate()})
      : geometric(mode, params, MakeSphereTool(), nullptr, objects),
        step(MakeSphereTool(), coupling, Eigen::Vector3d(0, 0, -kG_m_s2), kDt_s, start) {
    step.SetGeometricContact(&geometric);
  }
  GeometricHapticContact geometric;
  HapticStep step;
};

// Depth of the sphere's lowest point below the plate's top, m.
double Penetration_m(const ToolState& tool) { return kRadius_m - tool.x_W_m.z(); }

// ---- penalty --------------------------------------------------------------------------------

TEST(PenaltyMode, SteadyPenetrationIsThePressingForceOverK) {
  // Device held D = 4 mm below where the sphere would touch; the coupling k_c and gravity press
  // the tool in. At rest (ε = 0): k d = k_c (D − d) + m g, so d = (k_c D + m g)/(k + k_c).
  GeometricContactParams params;
  params.penalty.stiffness_N_m = 600.0;
  const double k_c = 300.0, D_m = 0.004;
  Rig rig(HapticMode::kPenalty, params, Coupling(k_c, 3.0), At({0, 0, kRadius_m + 0.002}));
  const DeviceState device = DeviceAt({0, 0, kRadius_m - D_m});
  HapticOutput out;
  for (int k = 0; k < 4000; ++k) out = rig.step.Step(device);
  const double expected_m = (k_c * D_m + kMass_kg * kG_m_s2) / (600.0 + k_c);
  EXPECT_NEAR(Penetration_m(rig.step.tool_state()), expected_m, 1e-7);
  // The contact force is k d (the paper's 0.6 N/mm), straight up.
  EXPECT_NEAR(out.contact_force_W_N.z(), 600.0 * expected_m, 1e-4);
  EXPECT_NEAR(out.contact_force_W_N.head<2>().norm(), 0.0, 1e-9);
}

struct ImpactRun {
  double max_penetration_m = 0.0;
  double max_force_change_N = 0.0;
};

// The device sweeps down at 0.5 m/s from 1 cm above the plate to 5 mm below where the sphere
// would touch, and stays; the tool follows through a stiff coupling.
ImpactRun RunPenaltyImpact(bool predictive_margin) {
  GeometricContactParams params;
  params.penalty.predictive_margin = predictive_margin;
  params.penalty.max_force_change_N = 0.3;
  const Eigen::Vector3d top(0, 0, kRadius_m + 0.01);
  Rig rig(HapticMode::kPenalty, params, Coupling(1000.0, 2.0), At(top));
  ImpactRun run;
  Eigen::Vector3d last_F = Eigen::Vector3d::Zero();
  const double v_m_s = 0.5;
  for (int k = 0; k < 1500; ++k) {
    const double z = std::max(top.z() - v_m_s * k * kDt_s, kRadius_m - 0.005);
    const bool moving = z > kRadius_m - 0.005;
    const HapticOutput out =
        rig.step.Step(DeviceAt({0, 0, z}, Eigen::Vector3d(0, 0, moving ? -v_m_s : 0.0)));
    run.max_penetration_m = std::max(run.max_penetration_m, Penetration_m(rig.step.tool_state()));
    run.max_force_change_N =
        std::max(run.max_force_change_N, (out.contact_force_W_N - last_F).norm());
    last_F = out.contact_force_W_N;
  }
  return run;
}

TEST(PenaltyMode, PredictiveMarginLowersThePenetrationOfAnImpact) {
  const ImpactRun with = RunPenaltyImpact(true);
  const ImpactRun without = RunPenaltyImpact(false);
  EXPECT_LT(with.max_penetration_m, without.max_penetration_m);
  // The margin is felt one step early at the approach speed: at least 0.1 mm less.
  EXPECT_LT(with.max_penetration_m, without.max_penetration_m - 1e-4)
      << with.max_penetration_m << " vs " << without.max_penetration_m;
}

TEST(PenaltyMode, ForceChangesByAtMostTheLimitPerStep) {
  for (bool margin : {true, false}) {
    const ImpactRun run = RunPenaltyImpact(margin);
    EXPECT_LE(run.max_force_change_N, 0.3 + 1e-12);
    EXPECT_GT(run.max_force_change_N, 0.15);  // the limit was reached: the test can fail
  }
}

TEST(PenaltyMode, LimitChangeFollowsThePaper) {
  const Eigen::Vector3d p(0, 0, 1);
  // Within F_max: the new force; within 2 F_max: the mean; beyond: F_max towards it.
  EXPECT_TRUE(contact::LimitChange(p, {0, 0, 1.05}, 0.1).isApprox(Eigen::Vector3d(0, 0, 1.05)));
  EXPECT_TRUE(contact::LimitChange(p, {0, 0, 1.15}, 0.1).isApprox(Eigen::Vector3d(0, 0, 1.075)));
  EXPECT_TRUE(contact::LimitChange(p, {0, 0, 2.0}, 0.1).isApprox(Eigen::Vector3d(0, 0, 1.1)));
}

// ---- impact ---------------------------------------------------------------------------------

// Apex of the tool's lowest point above the plate after its first bounce, for a free tool (no
// coupling) dropped from drop_m above the plate.
double RunDrop(double e, double drop_m) {
  GeometricContactParams params;
  params.impact.restitution = e;
  params.search_margin_m = 5e-3;  // ≥ |v| Δt at impact (1.4 m/s)
  Rig rig(HapticMode::kImpact, params, CouplingParams{}, At({0, 0, kRadius_m + drop_m}));
  const DeviceState idle;  // no coupling: the device does not act
  bool bounced = false;
  double apex_m = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const double vz_before = rig.step.tool_state().v_W_m_s.z();
    rig.step.Step(idle);
    const ToolState& tool = rig.step.tool_state();
    if (vz_before < 0.0 && tool.v_W_m_s.z() >= 0.0 && !bounced) bounced = true;
    if (bounced) {
      apex_m = std::max(apex_m, tool.x_W_m.z() - kRadius_m);
      if (tool.v_W_m_s.z() < 0.0) break;  // on its way down again
    }
  }
  EXPECT_TRUE(bounced);
  return apex_m;
}

TEST(ImpactMode, ToolReboundsToRestitutionSquaredOfItsDropHeight) {
  const double h_m = 0.1;
  const double v0_m_s = std::sqrt(2.0 * kG_m_s2 * h_m);
  for (double e : {0.0, 0.5, 1.0}) {
    const double apex_m = RunDrop(e, h_m);
    // The impact is resolved at the step it would cross, from up to |v| Δt above the surface,
    // and symplectic Euler under gravity is off by g Δt per step of position: bound below.
    const double bound_m = (1.0 + e * e) * v0_m_s * kDt_s + 2.0 * kG_m_s2 * kDt_s * kDt_s;
    EXPECT_NEAR(apex_m, e * e * h_m, bound_m) << "e = " << e;
  }
}

TEST(ImpactMode, RestingToolStaysOnThePlate) {
  GeometricContactParams params;
  params.impact.restitution = 1.0;  // resting contact must not bounce even with e = 1
  Rig rig(HapticMode::kImpact, params, CouplingParams{}, At({0, 0, kRadius_m}));
  for (int k = 0; k < 500; ++k) rig.step.Step(DeviceState{});
  EXPECT_NEAR(rig.step.tool_state().x_W_m.z(), kRadius_m, 1e-9);
  EXPECT_NEAR(rig.step.tool_state().v_W_m_s.norm(), 0.0, 1e-9);
}

// ---- material -------------------------------------------------------------------------------

GeometricContactParams MaterialParams(double friction_N_m, double stickiness_N) {
  GeometricContactParams params;
  params.material.max_stiffness_N_m = 800.0;
  params.material.tool.stiffness = 0.5;
  params.material.default_object.stiffness = 0.75;
  params.material.default_object.friction_N_m = friction_N_m;
  params.material.default_object.stickiness_N = stickiness_N;
  return params;
}

// The material force on a box tool held 1 mm into `objects` (and the pairs that collided).
Eigen::Vector3d MaterialForceOfBoxPress(const std::vector<contact::RigidObject>& objects,
                                        const std::vector<double>& stiffness = {},
                                        int* num_pairs = nullptr) {
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Eigen::Vector3d(0.01, 0.01, 0.005);
  const ToolModel tool = MakeToolModelWithMass(box, kMass_kg);
  GeometricContactParams params = MaterialParams(0, 0);
  for (double s : stiffness) {
    params.material.objects.push_back(params.material.default_object);
    params.material.objects.back().stiffness = s;
  }
  GeometricHapticContact geometric(HapticMode::kMaterial, params, tool, nullptr, objects);
  const ToolState state = At({0, 0, 0.005 - 0.001});
  ToolStepSystem system;
  system.dt_s = kDt_s;
  Eigen::Vector3d F, T;
  geometric.Calc(system, state, &F, &T);
  if (num_pairs != nullptr) *num_pairs = geometric.material().num_colliding_pairs();
  return F;
}

TEST(MaterialMode, TwoIdenticalPairsGiveTheForceOfOne) {
  // Hooke: k_max S₀ S₁ d = 800 · 0.5 · 0.75 · 1 mm = 0.3 N, up.
  const double expected_N = 800.0 * 0.5 * 0.75 * 0.001;
  const Eigen::Vector3d one = MaterialForceOfBoxPress({MakePlate()});
  EXPECT_NEAR(one.z(), expected_N, 1e-9);
  EXPECT_NEAR(one.head<2>().norm(), 0.0, 1e-9);
  // Two identical plates side by side, the tool across both: each pair alone gives 0.3 N; the
  // average of the two is the force of one (their sum would be 0.6 N).
  int pairs = 0;
  const Eigen::Vector3d two =
      MaterialForceOfBoxPress({MakePlate(0.05, -0.05), MakePlate(0.05, 0.05)}, {}, &pairs);
  EXPECT_EQ(pairs, 2);
  EXPECT_NEAR(two.z(), expected_N, 1e-9);
  // Two different plates (S₁ 0.75 and 0.25: 0.3 and 0.1 N alone): their mean, 0.2 N, neither the
  // sum (0.4 N) nor the larger (0.3 N).
  const Eigen::Vector3d mixed = MaterialForceOfBoxPress(
      {MakePlate(0.05, -0.05), MakePlate(0.05, 0.05)}, {0.75, 0.25}, &pairs);
  EXPECT_EQ(pairs, 2);
  EXPECT_NEAR(mixed.z(), 0.5 * (expected_N + 800.0 * 0.5 * 0.25 * 0.001), 1e-9);
}

TEST(MaterialMode, StickSlipSawtooth) {
  // A sphere 1 mm into a plate, slid along x in 0.1 mm steps: the tangential force is
  // F (x − x_stick) back towards the stored point until it would exceed the stickiness T; then
  // the point slips to the current one and the force drops to zero: peaks ≤ T, period T/(F δ).
  const double F_N_m = 500.0, T_N = 0.22;
  GeometricHapticContact geometric(HapticMode::kMaterial, MaterialParams(F_N_m, T_N),
                                   MakeSphereTool(), nullptr, {MakePlate()});
  ToolStepSystem system;
  system.dt_s = kDt_s;
  double x_stick_m = 0.0;
  int slips = 0;
  for (int k = 0; k <= 40; ++k) {
    const double x_m = 1e-4 * k;
    Eigen::Vector3d F, T;
    geometric.Calc(system, At({x_m, 0, kRadius_m - 0.001}), &F, &T);
    const double spring_N = F_N_m * (x_m - x_stick_m);
    if (spring_N > T_N) {  // slip: the stored point moves here, no tangential force this step
      x_stick_m = x_m;
      ++slips;
      EXPECT_NEAR(F.x(), 0.0, 1e-12) << k;
    } else {
      EXPECT_NEAR(F.x(), -spring_N, 1e-9) << k;
    }
    EXPECT_LE(std::abs(F.x()), T_N);
  }
  EXPECT_EQ(slips, 8);  // every 5th step from the 5th: 0.25 N > 0.22 N at 0.5 mm
}

// ---- no allocation --------------------------------------------------------------------------

// The body path: a 5 mm sphere pressed into a small soft block's surface snapshot (node and
// sphere-centre-versus-face contacts, the merge), every mode, no allocation after a warm-up.
TEST(GeometricModes, StepOnABodyAllocatesNothing) {
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocation counting is off (sanitizer)";
  const fem::Model block =
      fem::MakeModel(fem::MakeBoxTetMesh({-0.02, -0.02, -0.01}, {0.02, 0.02, 0.0}, {8, 8, 2}),
                     fem::Material{}, {});
  for (HapticMode mode : {HapticMode::kPenalty, HapticMode::kMaterial, HapticMode::kImpact}) {
    GeometricHapticContact geometric(mode, MaterialParams(500, 0.2), MakeSphereTool(), &block, {});
    HapticStep step(MakeSphereTool(), Coupling(300, 3), Eigen::Vector3d(0, 0, -kG_m_s2), kDt_s,
                    At({0.0013, 0.0007, kRadius_m + 0.001}));
    step.SetGeometricContact(&geometric);
    const auto device_at = [](int k) {
      return DeviceAt({0.004 * std::sin(0.01 * k), 0.0007, kRadius_m - 0.003 * std::sin(0.02 * k)});
    };
    for (int k = 0; k < 400; ++k) step.Step(device_at(k));  // warm-up: buffers grow
    AllocationCounter counter;
    int in_contact = 0;
    for (int k = 400; k < 800; ++k) {
      step.Step(device_at(k));
      in_contact += geometric.num_contacts() > 0 ? 1 : 0;
    }
    EXPECT_EQ(counter.count(), 0) << ToString(mode);
    EXPECT_GT(in_contact, 50) << ToString(mode);
  }
}

TEST(GeometricModes, StepAllocatesNothing) {
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocation counting is off (sanitizer)";
  for (HapticMode mode : {HapticMode::kPenalty, HapticMode::kMaterial, HapticMode::kImpact}) {
    Rig rig(mode, MaterialParams(500, 0.2), Coupling(300, 3), At({0, 0, kRadius_m + 0.001}));
    const auto device_at = [](int k) {
      return DeviceAt({0.01 * std::sin(0.01 * k), 0, kRadius_m - 0.003 * std::sin(0.02 * k)});
    };
    for (int k = 0; k < 400; ++k) rig.step.Step(device_at(k));  // warm-up: buffers grow
    AllocationCounter counter;
    int in_contact = 0;
    for (int k = 400; k < 800; ++k) {
      rig.step.Step(device_at(k));
      in_contact += rig.geometric.num_contacts() > 0 ? 1 : 0;
    }
    EXPECT_EQ(counter.count(), 0) << ToString(mode);
    EXPECT_GT(in_contact, 50) << ToString(mode);
  }
}

}  // namespace
}  // namespace hapsim::device
