// The in-process multirate simulator on a small press-slide-release scene, against the
// reference mode (everything at 1 kHz) as the independent value:
//  - the paper's linear contact model renders the device force closer to the reference than
//    standard multirate coupling at the same 30 Hz visual rate;
//  - release: equality constraints in the linear model pull the tool while it lifts off (the
//    sticking the paper reports), while unilateral contacts never pull, solved at 1 kHz by the
//    lcp mode or by the reference;
//  - the passivity energy is the work at the device port; a simulated hand closes the loop and
//    comes to rest where its arm balances the device force;
//  - runs are bit-reproducible; the haptic step allocates nothing, in the linear and lcp modes.
// (The same comparison on the block_press scene is tests/device/block_press_accuracy_test.cc.)
#include "device/multirate_simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fem/lattice_mesher.h"
#include "fem/time_stepper.h"
#include "tests/allocation_counter.h"

namespace hapsim::device {
namespace {

constexpr int kStepsPerFrame = 33;  // 30.3 Hz visual rate

struct Scene {
  fem::Model body;
  ToolModel tool;
  ToolState start;
};

Scene MakeScene(double youngs_modulus_Pa = 5e4) {
  const fem::TetMesh mesh = fem::MakeBoxTetMesh({-0.05, -0.05, 0}, {0.05, 0.05, 0.05}, {6, 6, 3});
  fem::Material material;
  material.youngs_modulus_Pa = youngs_modulus_Pa;
  material.poisson_ratio = 0.45;
  material.rayleigh_beta_s = 0.01;
  ToolShape shape;
  shape.kind = ToolShape::Kind::kCylinder;
  shape.radius_m = 0.02;
  shape.length_m = 0.04;
  Scene scene{
      fem::MakeModel(mesh, material, fem::FindNodesInBox(mesh, {-1, -1, -1}, {1, 1, 1e-9}, 0)),
      MakeToolModelWithMass(shape, 0.05), ToolState{}};
  scene.start.x_W_m = Eigen::Vector3d(0, 0, 0.071);  // bottom face 1 mm above the top
  return scene;
}

// Press 4 mm, slide 2 cm, lift (when `slide`), or press and lift straight up.
ScriptedTrajectory MakeScript(const ToolState& start, bool slide) {
  const Eigen::Quaterniond I = Eigen::Quaterniond::Identity();
  const Eigen::Vector3d down = start.x_W_m - Eigen::Vector3d(0, 0, 0.005);
  if (!slide)
    return ScriptedTrajectory({{0, start.x_W_m, I},
                               {0.8, down, I},
                               {1.2, down, I},
                               {2.0, start.x_W_m + Eigen::Vector3d(0, 0, 0.004), I}});
  const Eigen::Vector3d dx(0.02, 0, 0);
  return ScriptedTrajectory({{0, start.x_W_m, I},
                             {0.2, start.x_W_m, I},
                             {1.0, down, I},
                             {2.0, down + dx, I},
                             {2.8, start.x_W_m + dx, I},
                             {3.0, start.x_W_m + dx, I}});
}

// The scene's simulator at kStepsPerFrame haptic steps a frame, its coupling set in `visual`.
MultirateSimulator MakeSimulator(const Scene& scene, HapticMode mode,
                                 contact::VisualFrameOptions visual) {
  visual.coupling = {1000, 2, 1, 0.005};
  MultirateOptions options;
  options.mode = mode;
  options.haptic_steps_per_frame = kStepsPerFrame;
  return MultirateSimulator(scene.body, fem::FemOptions{},
                            fem::CalcGravityForce(scene.body, {0, 0, -9.81}), scene.tool,
                            scene.start, std::move(visual), options);
}

std::vector<HapticSample> Simulate(const Scene& scene, HapticMode mode, contact::ContactLaw law,
                                   const ScriptedTrajectory& script, long steps,
                                   DeviceBackend* device = nullptr) {
  contact::VisualFrameOptions visual;
  visual.response.solve.law = law;
  MultirateSimulator simulator = MakeSimulator(scene, mode, visual);
  std::vector<HapticSample> samples;
  ScriptedDevice scripted(script);
  simulator.Run(
      device ? device : &scripted, steps, [&](const HapticSample& s) { samples.push_back(s); },
      nullptr);
  return samples;
}

double RmsError(const std::vector<HapticSample>& a, const std::vector<HapticSample>& b) {
  double sum = 0.0;
  for (size_t k = 0; k < a.size(); ++k)
    sum += (a[k].device_force_W_N - b[k].device_force_W_N).squaredNorm();
  return std::sqrt(sum / a.size());
}

TEST(MultirateSimulator, LinearModelIsCloserToTheReferenceThanCoupling) {
  const Scene scene = MakeScene();
  const ScriptedTrajectory script = MakeScript(scene.start, true);
  const auto law = contact::ContactLaw::kUnilateral;
  const auto reference = Simulate(scene, HapticMode::kReference, law, script, 3000);
  const auto linear = Simulate(scene, HapticMode::kLinear, law, script, 3000);
  const auto coupling = Simulate(scene, HapticMode::kCoupling, law, script, 3000);
  const double linear_N = RmsError(linear, reference), coupling_N = RmsError(coupling, reference);
  RecordProperty("linear_rms_error_N", std::to_string(linear_N));
  RecordProperty("coupling_rms_error_N", std::to_string(coupling_N));
  EXPECT_LT(linear_N, coupling_N);
  // Both are errors of a working renderer, not of a broken one: well under the 3 N peak force.
  EXPECT_LT(coupling_N, 1.0);
}

double MinContactForceZWhileLifting(const std::vector<HapticSample>& samples) {
  double min_N = 0.0;
  for (const HapticSample& s : samples)
    if (s.t_s > 1.2) min_N = std::min(min_N, s.contact_force_W_N.z());
  return min_N;
}

TEST(MultirateSimulator, EqualityConstraintsStickOnReleaseUnilateralDoNot) {
  const Scene scene = MakeScene();
  const ScriptedTrajectory script = MakeScript(scene.start, false);
  const double equality_N = MinContactForceZWhileLifting(
      Simulate(scene, HapticMode::kLinear, contact::ContactLaw::kEquality, script, 2000));
  const double reference_N = MinContactForceZWhileLifting(
      Simulate(scene, HapticMode::kReference, contact::ContactLaw::kUnilateral, script, 2000));
  const std::vector<HapticSample> lcp =
      Simulate(scene, HapticMode::kLcp, contact::ContactLaw::kUnilateral, script, 2000);
  const double lcp_N = MinContactForceZWhileLifting(lcp);
  // The paper's linear model with unilateral contacts: the frame's active set acts as equalities
  // until the next frame, so it may pull in between; recorded, not asserted.
  const double linear_unilateral_N = MinContactForceZWhileLifting(
      Simulate(scene, HapticMode::kLinear, contact::ContactLaw::kUnilateral, script, 2000));
  RecordProperty("equality_min_force_z_N", std::to_string(equality_N));
  RecordProperty("linear_unilateral_min_force_z_N", std::to_string(linear_unilateral_N));
  EXPECT_LT(equality_N, -0.1);     // pulls the tool down while it lifts
  EXPECT_GE(reference_N, -1e-12);  // never pulls
  EXPECT_GE(lcp_N, -1e-12);
  for (const HapticSample& s : lcp) {
    ASSERT_FALSE(s.lcp_fell_back) << s.t_s;
  }
  // The lcp run did make contact (else "never pulls" says nothing).
  double max_push_N = 0.0;
  for (const HapticSample& s : lcp) max_push_N = std::max(max_push_N, s.contact_force_W_N.z());
  EXPECT_GT(max_push_N, 1.0);
}

// The passivity energy against its definition summed independently here, E = −Σ Δt F_k·v_k +
// m g·(x_k − x_0): the work at the device port, v_k the script's velocity at step k (open loop:
// the handle is the script), plus gravity's work on the tool, x_k the haptic tool after step k.
TEST(MultirateSimulator, PassivityEnergyIsTheWorkAtTheDevicePortAndOfGravity) {
  const Scene scene = MakeScene();
  const ScriptedTrajectory script = MakeScript(scene.start, true);
  const auto samples =
      Simulate(scene, HapticMode::kLinear, contact::ContactLaw::kUnilateral, script, 3000);
  const double weight_N = 9.81 * scene.tool.mass_kg;
  double port_J = 0.0, work_scale_J = 0.0;
  for (const HapticSample& s : samples) {
    const DeviceState device = script.Sample(s.t_s);
    port_J -= 1e-3 * s.device_force_W_N.dot(device.v_W_m_s);
    work_scale_J += 1e-3 * std::abs(s.device_force_W_N.dot(device.v_W_m_s));
    const double gravity_J = -weight_N * (s.tool_x_W_m.z() - scene.start.x_W_m.z());
    ASSERT_NEAR(s.passivity_energy_J, port_J + gravity_J, 1e-12 + 1e-9 * work_scale_J) << s.t_s;
    ASSERT_EQ(s.device_x_W_m, device.x_W_m);
  }
  EXPECT_GT(work_scale_J, 1e-3);  // the press did work at the port (else the check is empty)
}

// Issue 25 item 5: a tool lowered through free space gives the hand its weight's work, which the
// port's energy alone counts as generated. In every mode that renders a tool with weight, the
// observer stays quiet over a 9 cm descent that never reaches the body (its top is at 5 cm; the
// tool's bottom stops at 2 cm above it), while the port's energy alone, summed here, goes tens of
// millijoules below zero: without gravity's port the observer would fire (in every mode but
// coupling, whose port takes in more than the weight gives).
TEST(MultirateSimulator, PassivityObserverIsQuietWhileTheToolDescendsInFreeSpace) {
  const Scene scene = MakeScene();
  ToolState high = scene.start;
  high.x_W_m.z() = 0.18;  // bottom face at 16 cm
  const Eigen::Quaterniond I = Eigen::Quaterniond::Identity();
  const ScriptedTrajectory script({{0, high.x_W_m, I},
                                   {0.3, high.x_W_m, I},
                                   {1.3, high.x_W_m - Eigen::Vector3d(0, 0, 0.09), I},
                                   {2.0, high.x_W_m - Eigen::Vector3d(0, 0, 0.09), I}});
  Scene raised = scene;
  raised.start = high;
  for (const HapticMode mode :
       {HapticMode::kHybrid, HapticMode::kLinear, HapticMode::kLcp, HapticMode::kCoupling,
        HapticMode::kReference, HapticMode::kPenalty, HapticMode::kImpact}) {
    const auto samples = Simulate(raised, mode, contact::ContactLaw::kUnilateral, script, 2000);
    double port_J = 0.0, lowest_J = 0.0;
    for (const HapticSample& s : samples) {
      port_J -= 1e-3 * s.device_force_W_N.dot(script.Sample(s.t_s).v_W_m_s);
      lowest_J = std::min(lowest_J, s.passivity_energy_J);
      ASSERT_EQ(s.num_contacts, 0) << ToString(mode) << " " << s.t_s;  // free space throughout
    }
    // The coupling mode's hand drags a visual tool that moves once a frame (its spring lags the
    // descent and takes energy in): its port stays positive, with or without gravity's port.
    if (mode != HapticMode::kCoupling) {
      EXPECT_LT(port_J, -0.03) << ToString(mode) << ": the weight's work (≈ m g h = 44 mJ)";
    }
    EXPECT_GT(lowest_J, -1e-3) << ToString(mode);  // the observer's default threshold
  }
}

// ... and it still fires where the loop generates energy: the penalty mode's unstable cell of
// docs/RESULTS.md's map (k 38.4 N/mm at 1 kHz, a simulated hand pressing), where the observer
// turned active. Here the hand holds the tool 4 mm into the block.
TEST(MultirateSimulator, PassivityObserverFiresOnAnUnstablePenaltyLoop) {
  const Scene scene = MakeScene();
  const ScriptedTrajectory script = MakeScript(scene.start, false);
  for (const double k_N_m : {600.0, 38400.0}) {
    contact::VisualFrameOptions visual;
    visual.coupling = {1000, 2, 1, 0.005};
    MultirateOptions options;
    options.mode = HapticMode::kPenalty;
    options.haptic_steps_per_frame = 20;  // 50 Hz, as the map
    options.geometric.penalty.stiffness_N_m = k_N_m;
    MultirateSimulator simulator(scene.body, fem::FemOptions{},
                                 fem::CalcGravityForce(scene.body, {0, 0, -9.81}), scene.tool,
                                 scene.start, visual, options);
    SimulatedHand hand(script, HandParams{}, 1e-3);
    simulator.Run(&hand, 1200, nullptr, nullptr);
    EXPECT_EQ(simulator.passivity().active(), k_N_m > 1000.0) << k_N_m;
  }
}

// Closed loop: a simulated hand pulled along the script by its arm (k, b) and pushed by the
// device force. Holding the press, the hand comes to rest where its arm balances the force:
// k (x_target − x) + F = 0, the hand's own static equilibrium.
TEST(MultirateSimulator, SimulatedHandBalancesTheDeviceForce) {
  const Scene scene = MakeScene();
  const ScriptedTrajectory script = MakeScript(scene.start, false);  // held pressed 0.8–1.2 s
  HandParams hand;                                                   // 0.3 kg, 300 N/m, 10 N s/m
  SimulatedHand device(script, hand, 1e-3);
  const auto samples =
      Simulate(scene, HapticMode::kLinear, contact::ContactLaw::kUnilateral, script, 1200, &device);
  const HapticSample& last = samples.back();
  const Eigen::Vector3d target_m = script.Sample(last.t_s).x_W_m;
  const Eigen::Vector3d arm_N = hand.k_N_m * (target_m - last.device_x_W_m);
  EXPECT_GT(last.device_force_W_N.z(), 0.5);              // pressed: the body pushes back
  EXPECT_GT(last.device_x_W_m.z() - target_m.z(), 1e-3);  // and the hand yields millimetres
  EXPECT_NEAR((arm_N + last.device_force_W_N).norm(), 0.0, 0.02 * last.device_force_W_N.norm());
}

// Issue 25 item 1: a tool driven at 1 m/s (the device 6 mm down in 6 ms) into a stiff block
// (E 5 MPa: it hardly yields) at 30 Hz. The haptic tool may sink below the block's top by what
// the visual tool sinks (the frames' own contact) plus at most 1 mm. The default mode holds it
// there: the frame's other candidate rows, switched on when the tool reaches them. The paper's
// linear model alone lets it through (its model holds only the last frame's active contacts,
// none before the first touch): the same check fails it, so the check can fail.
double FastPressPenetration(HapticMode mode, double* visual_sink_m) {
  const Scene scene = MakeScene(5e6);
  const Eigen::Quaterniond I = Eigen::Quaterniond::Identity();
  const Eigen::Vector3d start = scene.start.x_W_m, down = start - Eigen::Vector3d(0, 0, 0.006);
  const ScriptedTrajectory script(
      {{0, start, I}, {0.05, start, I}, {0.056, down, I}, {0.4, down, I}});
  contact::VisualFrameOptions visual;
  visual.model_compliance_step = contact::ModelComplianceStep::kAuto;  // a scene's default
  MultirateSimulator simulator = MakeSimulator(scene, mode, visual);
  const double top_plus_half_m = 0.05 + 0.02;  // the tool's COM when its bottom face is on top
  double haptic_depth_m = 0.0;
  *visual_sink_m = 0.0;
  simulator.Run(
      script, 400,
      [&](const HapticSample& s) {
        haptic_depth_m = std::max(haptic_depth_m, top_plus_half_m - s.tool_x_W_m.z());
      },
      [&](const FrameSample& f) {
        *visual_sink_m = std::max(*visual_sink_m, top_plus_half_m - f.tool_x_W_m.z());
      });
  return haptic_depth_m - *visual_sink_m;
}

TEST(MultirateSimulator, DefaultModeHoldsAFastToolOnAStiffBlock) {
  EXPECT_EQ(MultirateOptions{}.mode, HapticMode::kHybrid);  // the default is what is tested
  double visual_sink_m = 0.0;
  const double hybrid_m = FastPressPenetration(MultirateOptions{}.mode, &visual_sink_m);
  RecordProperty("hybrid_penetration_m", std::to_string(hybrid_m));
  EXPECT_LE(hybrid_m, 1e-3) << "visual sink " << visual_sink_m;
  EXPECT_LT(visual_sink_m, 1e-3);  // the block is stiff: the frames hold the visual tool
  const double linear_m = FastPressPenetration(HapticMode::kLinear, &visual_sink_m);
  RecordProperty("linear_penetration_m", std::to_string(linear_m));
  EXPECT_GT(linear_m, 1e-3) << "the paper's model alone tunnels here";
}

TEST(MultirateSimulator, RunsAreBitReproducible) {
  const Scene scene = MakeScene();
  const ScriptedTrajectory script = MakeScript(scene.start, false);
  for (const HapticMode mode : {HapticMode::kLinear, HapticMode::kHybrid}) {
    const auto a = Simulate(scene, mode, contact::ContactLaw::kUnilateral, script, 1000);
    const auto b = Simulate(scene, mode, contact::ContactLaw::kUnilateral, script, 1000);
    for (size_t k = 0; k < a.size(); ++k)
      ASSERT_EQ(a[k].device_force_W_N, b[k].device_force_W_N) << ToString(mode) << " " << k;
  }
}

// contact.model_compliance_step `auto`: the haptic step's compliance for the hybrid mode below
// 100 Hz, the visual step's at and above it and for every other mode; an explicit choice stands.
TEST(ResolveModelComplianceStep, ChoosesByModeAndVisualRate) {
  using contact::ModelComplianceStep;
  const auto resolve = [](ModelComplianceStep step, HapticMode mode, double hz) {
    return ResolveModelComplianceStep(step, mode, 1.0 / hz);
  };
  EXPECT_EQ(resolve(ModelComplianceStep::kAuto, HapticMode::kHybrid, 33.3),
            ModelComplianceStep::kHaptic);
  EXPECT_EQ(resolve(ModelComplianceStep::kAuto, HapticMode::kHybrid, 99.0),
            ModelComplianceStep::kHaptic);
  EXPECT_EQ(resolve(ModelComplianceStep::kAuto, HapticMode::kHybrid, 100.0),
            ModelComplianceStep::kVisual);
  EXPECT_EQ(resolve(ModelComplianceStep::kAuto, HapticMode::kHybrid, 200.0),
            ModelComplianceStep::kVisual);
  for (const HapticMode mode : {HapticMode::kLinear, HapticMode::kLcp, HapticMode::kReference})
    EXPECT_EQ(resolve(ModelComplianceStep::kAuto, mode, 33.3), ModelComplianceStep::kVisual);
  EXPECT_EQ(resolve(ModelComplianceStep::kVisual, HapticMode::kHybrid, 33.3),
            ModelComplianceStep::kVisual);
  EXPECT_EQ(resolve(ModelComplianceStep::kHaptic, HapticMode::kLinear, 200.0),
            ModelComplianceStep::kHaptic);
}

// What a mode needs of the frame, set in one place for sim, run and inspect: the steps, the
// candidate rows for the modes that solve them at 1 kHz, the resolved compliance step, and the
// reference's exact compliance with the scene's own CG tolerance for the correction.
TEST(SetUpFrameForMode, GivesEachModeWhatItNeeds) {
  contact::VisualFrameOptions scene_options;
  scene_options.model_compliance_step = contact::ModelComplianceStep::kAuto;
  const auto hybrid = SetUpFrameForMode(scene_options, HapticMode::kHybrid, 0.03, 1e-3);
  EXPECT_EQ(hybrid.dt_s, 0.03);
  EXPECT_EQ(hybrid.haptic_dt_s, 1e-3);
  EXPECT_TRUE(hybrid.export_contact_rows);
  EXPECT_EQ(hybrid.model_compliance_step, contact::ModelComplianceStep::kHaptic);
  EXPECT_EQ(hybrid.compliance, contact::ComplianceMethod::kWarped);
  const auto linear = SetUpFrameForMode(scene_options, HapticMode::kLinear, 0.03, 1e-3);
  EXPECT_FALSE(linear.export_contact_rows);
  EXPECT_EQ(linear.model_compliance_step, contact::ModelComplianceStep::kVisual);
  EXPECT_EQ(linear.correction_relative_tolerance, scene_options.correction_relative_tolerance);
  const auto reference = SetUpFrameForMode(scene_options, HapticMode::kReference, 1e-3, 1e-3);
  EXPECT_EQ(reference.compliance, contact::ComplianceMethod::kExact);
  EXPECT_EQ(reference.correction_relative_tolerance, 0.0);
  EXPECT_EQ(reference.free_body_correction_relative_tolerance, 0.0);
}

TEST(HapticStep, AllocatesNothing) {
  const Scene scene = MakeScene();
  HapticStep step(scene.tool, {1000, 2, 1, 0.005}, {0, 0, -9.81}, 1e-3, scene.start);
  contact::LinearContactModel model;
  model.F_c0_N = Eigen::Vector3d(0, 0, 1);
  model.dFc_dF = -0.5 * Eigen::Matrix3d::Identity();
  model.num_contacts = 10;
  const ScriptedTrajectory script = MakeScript(scene.start, true);
  step.Step(script.Sample(0.0));  // warm-up
  AllocationCounter counter;
  for (int k = 1; k < 1000; ++k) {
    if (k % 33 == 0) step.SetContactModel(model);
    step.Step(script.Sample(k * 1e-3));
  }
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations not counted (sanitizer build)";
  EXPECT_EQ(counter.count(), 0);
}

// 40 contact rows under the tool's flat bottom face (normals up the body, J_v = −n = −z) with a
// symmetric positive definite body compliance; the lcp step solves them each ms.
contact::ContactRows MakeRows() {
  const int n = 40;
  contact::ContactRows rows;
  rows.J_v.resize(n, 3);
  rows.J_w.resize(n, 3);
  rows.body_rhs.resize(n);
  Eigen::MatrixXd B = Eigen::MatrixXd::Random(n, n);
  rows.W_body = 1e-3 * (B * B.transpose() / n + Eigen::MatrixXd::Identity(n, n));
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d normal(0, 0, -1);  // tool's outward normal on its bottom face
    const Eigen::Vector3d r(0.015 * std::cos(i), 0.015 * std::sin(i), -0.02);
    rows.J_v.row(i) = -normal.transpose();
    rows.J_w.row(i) = -r.cross(normal).transpose();
    rows.body_rhs[i] = i % 3 == 0 ? 1e-3 : -1e-3;  // some rows push, some are slack
  }
  return rows;
}

// The hybrid step's free rows follow the tool (HapticStep::CalcFreeRowTargets). One row the frame
// did not find active: a rigid floor 1 mm below the tool's bottom (gap φ = 1 mm, the frame's gap
// target −φ/Δt_visual at 30 Hz, a still surface). The device lowers the tool slowly, 5 mm/s, to
// 3 mm below the start: the row must stay off while the tool's tracked gap is open (no force
// above the floor) and hold the tool at the floor once it reaches it (the coupling then presses
// 2 mm: k_c·2 mm + m g). With the frame's own target (approach faster than φ/Δt_visual = 33
// mm/s to engage) the row would never engage at this speed and the tool would sink through.
TEST(HapticStep, HybridFreeRowEngagesWhereTheToolReachesIt) {
  const Scene scene = MakeScene();
  const double k_N_m = 1000.0;
  HapticStep step(scene.tool, {k_N_m, 2, 1, 0.005}, {0, 0, -9.81}, 1e-3, scene.start, 4, 0, true);
  contact::ContactRows rows;
  rows.J_v = Eigen::RowVector3d(0, 0, 1);  // −nᵀ, n = −z out of the tool's bottom face
  rows.J_w = Eigen::RowVector3d::Zero();
  rows.W_body = Eigen::MatrixXd::Constant(1, 1, 1e-6);  // nearly rigid
  const double gap_m = 1e-3, dt_visual_s = 1.0 / 30.0;
  rows.gap_m = Eigen::VectorXd::Constant(1, gap_m);
  rows.gap_target_m_s = Eigen::VectorXd::Constant(1, -gap_m / dt_visual_s);
  rows.surface_velocity_m_s = Eigen::VectorXd::Zero(1);
  rows.body_rhs = rows.gap_target_m_s;  // b − the surface's velocity (0)
  rows.lambda_frame_N = Eigen::VectorXd::Zero(1);
  step.SetContactRows(&rows);  // linearised at the tool as it stands: the gap is from here
  const Eigen::Quaterniond I = Eigen::Quaterniond::Identity();
  const Eigen::Vector3d start = scene.start.x_W_m;
  const ScriptedTrajectory script({{0, start, I},
                                   {0.6, start - Eigen::Vector3d(0, 0, 0.003), I},
                                   {1.0, start - Eigen::Vector3d(0, 0, 0.003), I}});
  const double floor_z_m = start.z() - gap_m;
  double lowest_z_m = start.z(), force_above_floor_N = 0.0;
  HapticOutput out;
  for (int k = 0; k < 1000; ++k) {
    const double z_before_m = step.tool_state().x_W_m.z();
    out = step.Step(script.Sample(k * 1e-3));
    ASSERT_FALSE(out.lcp_fell_back) << k;
    lowest_z_m = std::min(lowest_z_m, step.tool_state().x_W_m.z());
    // A step that starts more than one step's travel (5 µm, 10 µm for margin) above the floor.
    if (z_before_m > floor_z_m + 1e-5)
      force_above_floor_N = std::max(force_above_floor_N, out.contact_force_W_N.norm());
  }
  EXPECT_EQ(force_above_floor_N, 0.0);
  EXPECT_GE(lowest_z_m, floor_z_m - 1e-5);  // held at the floor (W_body lets it in ~µm)
  // Resting on it, held 2 mm down: the floor carries the coupling's k_c·2 mm and the weight.
  EXPECT_NEAR(out.contact_force_W_N.z(), k_N_m * 0.002 + 9.81 * scene.tool.mass_kg, 0.02);
}

// Steps through 1,000 steps on rows_a and rows_b, alternating every 33 steps (a new frame).
void ExpectStepAllocatesNothing(const Scene& scene, HapticStep* step,
                                const contact::ContactRows& rows_a,
                                const contact::ContactRows& rows_b) {
  const ScriptedTrajectory script = MakeScript(scene.start, true);
  step->SetContactRows(&rows_a);
  step->Step(script.Sample(0.0));  // warm-up
  AllocationCounter counter;
  int pushes = 0;
  for (int k = 1; k < 1000; ++k) {
    if (k % 33 == 0) step->SetContactRows((k / 33) % 2 ? &rows_b : &rows_a);  // a new frame
    const HapticOutput out = step->Step(script.Sample(k * 1e-3));
    ASSERT_FALSE(out.lcp_fell_back) << k;
    pushes += out.contact_force_W_N.z() > 0.0;
  }
  const std::int64_t allocations = counter.count();
  EXPECT_GT(pushes, 0);  // the rows did act on the tool
  if (AllocationCounter::enabled()) {
    EXPECT_EQ(allocations, 0);
  }
}

// The lcp step, and the hybrid step with held rows and free rows that follow the tool (their
// targets recomputed every step).
TEST(HapticStep, LcpAndHybridStepsAllocateNothing) {
  for (const bool hybrid : {false, true}) {
    SCOPED_TRACE(hybrid ? "hybrid" : "lcp");
    const Scene scene = MakeScene();
    HapticStep step(scene.tool, {1000, 2, 1, 0.005}, {0, 0, -9.81}, 1e-3, scene.start, 64, 0,
                    hybrid);
    contact::ContactRows rows_a = MakeRows();
    if (hybrid) {
      const int n = rows_a.num_rows();
      rows_a.lambda_frame_N = Eigen::VectorXd::Zero(n);
      for (int i = 0; i < n; i += 3) rows_a.lambda_frame_N[i] = 1.0;  // the pushing rows held
      rows_a.gap_m = Eigen::VectorXd::Constant(n, 2e-4);
      rows_a.gap_target_m_s = Eigen::VectorXd::Constant(n, -2e-4 / 0.033);
      rows_a.surface_velocity_m_s = Eigen::VectorXd::Zero(n);
    }
    contact::ContactRows rows_b = rows_a;
    rows_b.body_rhs *= -1.0;
    ExpectStepAllocatesNothing(scene, &step, rows_a, rows_b);
  }
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations not counted (sanitizer build)";
}

}  // namespace
}  // namespace hapsim::device
