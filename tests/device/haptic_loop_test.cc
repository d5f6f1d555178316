// Tests of device/haptic_loop.h, device/model_mailbox.h and device/device_backend.h:
//  - two loops fed the same (device state, device age, model) sequence send bit-identical
//    wrenches (the basis of `hapsim replay`);
//  - a NaN device state sends exactly zero, leaves the haptic tool untouched, and the output
//    ramps back within the rate limit; the force clamp holds over a whole run;
//  - a model that is no longer refreshed is felt in full before model_stale_s/2 and not at all
//    from model_stale_s on;
//  - the lcp mode never pulls the tool and allocates nothing per step;
//  - the papers' 1 kHz modes render the world each model carries, allocating nothing;
//  - the triple buffer: its single-threaded semantics, and no torn or out-of-order value under
//    a two-thread stress;
//  - SimulatedHand against a spring wall: the static equilibrium of the two springs, and energy
//    conservation without damping (symplectic Euler does not drift).

#include "device/haptic_loop.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <thread>
#include <vector>

#include "device/device_backend.h"
#include "device/model_mailbox.h"
#include "fem/lattice_mesher.h"
#include "tests/allocation_counter.h"

namespace hapsim::device {
namespace {

constexpr double kDt_s = 1e-3;
constexpr int kStepsPerFrame = 33;  // a 30 Hz visual process
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// The safety layer's outputs are a few products and sums of O(10) values: rounding is ~1e-15.
constexpr double kTolerance = 1e-12;
const CouplingParams kCoupling{1000, 2, 1, 0.005};
const Eigen::Vector3d kGravity(0, 0, -9.81);

ToolModel MakeTool() {
  ToolShape shape;
  shape.kind = ToolShape::Kind::kCylinder;
  shape.radius_m = 0.02;
  shape.length_m = 0.04;
  return MakeToolModelWithMass(shape, 0.05);
}

// Press 5 mm from the origin over 0.8 s, hold, lift 1 cm above the start by 2 s.
ScriptedTrajectory MakePressScript() {
  const Eigen::Quaterniond I = Eigen::Quaterniond::Identity();
  return ScriptedTrajectory({{0.0, Eigen::Vector3d::Zero(), I},
                             {0.8, Eigen::Vector3d(0, 0, -0.005), I},
                             {1.2, Eigen::Vector3d(0, 0, -0.005), I},
                             {2.0, Eigen::Vector3d(0, 0, 0.01), I}});
}

// A model that pushes the tool up with push_N whatever it does (no derivatives).
ContactModelUpdate MakePush(double push_N) {
  ContactModelUpdate update;
  update.sequence = 0;
  update.model.F_c0_N = Eigen::Vector3d(0, 0, push_N);
  update.model.num_contacts = 1;
  return update;
}

HapticLoopOptions Options(HapticMode mode = HapticMode::kLinear) {
  HapticLoopOptions options;
  options.mode = mode;
  options.dt_s = kDt_s;
  options.lcp_max_rows = 64;
  return options;
}

HapticLoop MakeLoop(const HapticLoopOptions& options) {
  return HapticLoop(MakeTool(), kCoupling, kGravity, ToolState{}, options);
}

// ---------------------------------------------------------------------------------------------

TEST(HapticLoop, SameInputsGiveBitIdenticalOutputs) {
  std::array<ContactModelUpdate, 2> models;
  models[0].model.F_c0_N = Eigen::Vector3d(0, 0, 2);  // a stiff floor
  models[0].model.dFc_dF = -0.9 * Eigen::Matrix3d::Identity();
  models[0].model.num_contacts = 4;
  models[1].model.F_c0_N = Eigen::Vector3d(0.3, -0.2, 1.0);  // a tilted, rotating contact
  models[1].model.T_c0_N_m = Eigen::Vector3d(0.01, 0.02, -0.01);
  models[1].model.dFc_dF << -0.5, 0.1, 0, 0.1, -0.6, 0.05, 0, 0.05, -0.8;
  models[1].model.dFc_dT = 0.3 * Eigen::Matrix3d::Identity();
  models[1].model.dTc_dF = 0.01 * Eigen::Matrix3d::Ones();
  models[1].model.dTc_dT = -0.4 * Eigen::Matrix3d::Identity();
  models[1].model.num_contacts = 3;
  const ScriptedTrajectory script = MakePressScript();
  // The two loops are stepped in turn, so shared state between instances would show.
  HapticLoop a = MakeLoop(Options()), b = MakeLoop(Options());
  double max_force_N = 0.0, max_torque_N_m = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const DeviceState device = script.Sample(k * kDt_s);
    const double age_s = (k % 4) * 1e-3;  // a jittery device clock, within device_stale_s
    const ContactModelUpdate* update =
        k % kStepsPerFrame == 0 ? &models[(k / kStepsPerFrame) % 2] : nullptr;
    const HapticLoopOutput out_a = a.Step(device, age_s, update);
    const HapticLoopOutput out_b = b.Step(device, age_s, update);
    for (int i = 0; i < 3; ++i) {
      ASSERT_EQ(out_a.sent.force_W_N[i], out_b.sent.force_W_N[i]) << k;
      ASSERT_EQ(out_a.sent.torque_W_N_m[i], out_b.sent.torque_W_N_m[i]) << k;
    }
    max_force_N = std::max(max_force_N, out_a.sent.force_W_N.norm());
    max_torque_N_m = std::max(max_torque_N_m, out_a.sent.torque_W_N_m.norm());
  }
  // The comparison was of a wrench that was rendered, not of zeros.
  EXPECT_GT(max_force_N, 0.1);
  EXPECT_GT(max_torque_N_m, 1e-4);
}

void ExpectSameToolState(const ToolState& a, const ToolState& b) {
  EXPECT_EQ(a.x_W_m, b.x_W_m);
  EXPECT_EQ(a.v_W_m_s, b.v_W_m_s);
  EXPECT_EQ(a.q_WT.coeffs(), b.q_WT.coeffs());
  EXPECT_EQ(a.L_W_kg_m2_s, b.L_W_kg_m2_s);
}

TEST(HapticLoop, NaNDeviceStateSendsZeroAndRampsBackWithinTheRateLimit) {
  HapticLoopOptions options = Options();
  options.safety.max_force_rate_N_s = 100.0;  // 0.1 N a step: the 4.5 N return is rate limited
  options.safety.model_stale_s = 100.0;       // one model for the whole run
  HapticLoop loop = MakeLoop(options);
  const ContactModelUpdate push = MakePush(5.0);
  const ScriptedTrajectory script = MakePressScript();
  const double max_step_N = options.safety.max_force_rate_N_s * kDt_s + kTolerance;
  constexpr int kNaNStep = 700;
  Eigen::Vector3d last_N = Eigen::Vector3d::Zero();
  HapticLoopOutput out;
  for (int k = 0; k < kNaNStep + 300; ++k) {
    DeviceState device = script.Sample(k * kDt_s);
    if (k == kNaNStep) device.x_W_m.x() = kNaN;
    const ToolState before = loop.tool_state();
    out = loop.Step(device, 0.0, k == 0 ? &push : nullptr);
    if (k == kNaNStep) {
      EXPECT_GT(last_N.norm(), 4.0);  // the tool was pushing on the hand
      EXPECT_EQ(out.sent.force_W_N, Eigen::Vector3d::Zero());
      EXPECT_EQ(out.sent.torque_W_N_m, Eigen::Vector3d::Zero());
      EXPECT_EQ(out.sent.state, SafetyState::kNonFiniteDevice) << ToString(out.sent.state);
      EXPECT_TRUE(out.sent.zeroed);
      ExpectSameToolState(loop.tool_state(), before);
    } else {
      // From zero at the start and after the NaN: never faster than the rate limit.
      ASSERT_LE((out.sent.force_W_N - last_N).norm(), max_step_N) << k;
      ASSERT_FALSE(out.sent.zeroed) << k;
    }
    last_N = out.sent.force_W_N;
  }
  // Ramped back in: once the ramp is over what is sent is what is rendered.
  EXPECT_EQ(out.sent.state, SafetyState::kOk) << ToString(out.sent.state);
  EXPECT_EQ(out.sent.force_W_N, out.rendered.device_force_W_N);
}

TEST(HapticLoop, ForceClampHoldsOverAWholeRun) {
  HapticLoopOptions options = Options();
  options.safety.max_force_N = 1.0;
  HapticLoop loop = MakeLoop(options);
  const ContactModelUpdate push = MakePush(5.0);  // ≈ 5 N − m g = 4.5 N on the hand at rest
  const ScriptedTrajectory script = MakePressScript();
  double max_sent_N = 0.0, max_rendered_N = 0.0;
  for (int k = 0; k < 3000; ++k) {
    const HapticLoopOutput out =
        loop.Step(script.Sample(k * kDt_s), 0.0, k % kStepsPerFrame == 0 ? &push : nullptr);
    ASSERT_LE(out.sent.force_W_N.norm(), options.safety.max_force_N + kTolerance) << k;
    max_sent_N = std::max(max_sent_N, out.sent.force_W_N.norm());
    max_rendered_N = std::max(max_rendered_N, out.rendered.device_force_W_N.norm());
  }
  EXPECT_GT(max_rendered_N, 4.0);  // the clamp had something to do
  EXPECT_NEAR(max_sent_N, options.safety.max_force_N, 1e-9);
}

TEST(HapticLoop, ModelFadesOutAndIsZeroFromModelStaleOn) {
  const HapticLoopOptions options = Options();
  HapticLoop loop = MakeLoop(options);
  const ContactModelUpdate push = MakePush(5.0);
  const ScriptedTrajectory script = MakePressScript();
  constexpr int kLastModelStep = 33 * 40;  // 1.32 s: the tool has settled on the model
  // Steps after the last model, counted here, not read from the loop.
  const int half_stale_steps =
      static_cast<int>(std::lround(0.5 * options.safety.model_stale_s / kDt_s));
  const int stale_steps = static_cast<int>(std::lround(options.safety.model_stale_s / kDt_s));
  for (int k = 0; k <= kLastModelStep + 3 * stale_steps; ++k) {
    const bool model = k <= kLastModelStep && k % kStepsPerFrame == 0;
    const HapticLoopOutput out = loop.Step(script.Sample(k * kDt_s), 0.0, model ? &push : nullptr);
    const int since = k - kLastModelStep;
    if (since >= 0 && since < half_stale_steps) {
      ASSERT_GT(out.sent.force_W_N.norm(), 4.0) << since;  // felt in full
    } else if (since >= stale_steps) {
      ASSERT_EQ(out.sent.force_W_N, Eigen::Vector3d::Zero()) << since;
      ASSERT_EQ(out.sent.torque_W_N_m, Eigen::Vector3d::Zero()) << since;
      ASSERT_EQ(out.sent.state, SafetyState::kModelStale) << since;
    }
  }
}

// Normal rows under the tool's flat bottom face (the tool's outward normal n = −z, J_v = −nᵀ),
// a floor that stops the tool moving down (body_rhs = 0) with a small diagonal compliance.
contact::ContactRows MakeFloorRows(int n, double compliance_per_kg) {
  contact::ContactRows rows;
  rows.J_v.resize(n, 3);
  rows.J_w.resize(n, 3);
  rows.W_body = compliance_per_kg * Eigen::MatrixXd::Identity(n, n);
  rows.body_rhs = Eigen::VectorXd::Zero(n);
  const Eigen::Vector3d normal(0, 0, -1);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d r(0.015 * std::cos(2.0 * i), 0.015 * std::sin(2.0 * i), -0.02);
    rows.J_v.row(i) = -normal.transpose();
    rows.J_w.row(i) = -r.cross(normal).transpose();
  }
  return rows;
}

TEST(HapticLoop, LcpModeNeverPullsAndAllocatesNothing) {
  HapticLoop loop = MakeLoop(Options(HapticMode::kLcp));
  std::array<ContactModelUpdate, 2> frames;  // two frames with different rows, alternating
  frames[0].rows = MakeFloorRows(6, 1e-3);
  frames[1].rows = MakeFloorRows(8, 2e-3);
  const ScriptedTrajectory script = MakePressScript();
  loop.Step(script.Sample(0.0), 0.0, &frames[0]);  // first step
  AllocationCounter counter;
  double min_z_N = 0.0, press_z_N = 0.0;
  int separated_steps = 0;
  for (int k = 1; k < 2000; ++k) {
    const ContactModelUpdate* update =
        k % kStepsPerFrame == 0 ? &frames[(k / kStepsPerFrame) % 2] : nullptr;
    const HapticLoopOutput out = loop.Step(script.Sample(k * kDt_s), 0.0, update);
    ASSERT_FALSE(out.rendered.lcp_fell_back) << k;
    const double z_N = out.rendered.contact_force_W_N.z();
    min_z_N = std::min(min_z_N, z_N);
    if (k == 1150) press_z_N = z_N;  // holding 5 mm down
    separated_steps += k > 1200 && z_N == 0.0;
  }
  const std::int64_t allocations = counter.count();
  EXPECT_GE(min_z_N, -kTolerance);  // never pulls
  // Held 5 mm under a tool the floor stops: the floor carries the coupling spring and gravity,
  // k_c·5 mm + m g = 5.49 N (the compliance lets the tool sink by micrometres only).
  EXPECT_NEAR(press_z_N, 1000 * 0.005 + 0.05 * 9.81, 0.05);
  EXPECT_GT(separated_steps, 100);  // lifting: the contacts let go
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations not counted (sanitizer build)";
  EXPECT_EQ(allocations, 0);
}

// Issue 25 item 5, in the haptic process's loop: a tool lowered 9 cm through free space (models
// with no contact) gives the hand its weight's work, m g h = 44 mJ; the port's energy alone, summed
// here, goes that far below zero, and the observer, which counts gravity's work on the haptic
// tool as energy in, stays quiet (no alarm, E above its threshold).
TEST(HapticLoop, PassivityObserverIsQuietWhileTheToolDescendsInFreeSpace) {
  const Eigen::Quaterniond I = Eigen::Quaterniond::Identity();
  const ScriptedTrajectory script({{0.0, Eigen::Vector3d::Zero(), I},
                                   {0.2, Eigen::Vector3d::Zero(), I},
                                   {1.2, Eigen::Vector3d(0, 0, -0.09), I},
                                   {1.8, Eigen::Vector3d(0, 0, -0.09), I}});
  ContactModelUpdate empty;  // a frame that found no contact
  empty.sequence = 0;
  for (const HapticMode mode : {HapticMode::kHybrid, HapticMode::kLinear, HapticMode::kLcp}) {
    HapticLoop loop = MakeLoop(Options(mode));
    double port_J = 0.0, lowest_J = 0.0;
    bool alarm = false;
    for (int k = 0; k < 1800; ++k) {
      const DeviceState device = script.Sample(k * kDt_s);
      const HapticLoopOutput out =
          loop.Step(device, 0.0, k % kStepsPerFrame == 0 ? &empty : nullptr);
      port_J -= kDt_s * out.sent.force_W_N.dot(device.v_W_m_s);
      lowest_J = std::min(lowest_J, out.passivity_energy_J);
      alarm = alarm || out.passivity_alarm;
    }
    EXPECT_LT(port_J, -0.03) << ToString(mode);
    EXPECT_GT(lowest_J, -1e-3) << ToString(mode);
    EXPECT_FALSE(alarm) << ToString(mode);
  }
}

// The papers' 1 kHz modes in the loop (docs/HAPTIC_MODES.md): each contact model carries the
// frame's world, which the loop puts in place before the step. A plate (top at z = h, h = 0 or
// 1 mm in alternate worlds) under a device point held 2 mm below z = 0, and a small soft block
// elsewhere whose nodes each world moves (the body's tree is refitted). The god-object's force
// follows the plate: k (h + r + ε − z_device) exactly; penalty's is the springs' in series for
// each height. No step allocates, world updates included.
TEST(HapticLoop, PapersModesRenderTheWorldEachModelCarriesAndAllocateNothing) {
  const fem::Model block = fem::MakeModel(
      fem::MakeBoxTetMesh({0.1, 0.1, 0.0}, {0.12, 0.12, 0.01}, {2, 2, 1}), fem::Material{}, {});
  contact::RigidObject plate;
  plate.name = "plate";
  plate.shape.kind = ToolShape::Kind::kBox;
  plate.shape.half_extents_m = Eigen::Vector3d(0.05, 0.05, 0.005);
  plate.X_WO.translation() = Eigen::Vector3d(0, 0, -0.005);
  std::array<ContactModelUpdate, 2> frames;
  for (int f = 0; f < 2; ++f) {
    frames[f].has_world = true;
    frames[f].body_x_m = block.rest_positions_m;
    for (int n = 0; n < block.num_nodes(); ++n) frames[f].body_x_m[3 * n + 2] += 1e-3 * f;
    frames[f].object_poses = {plate.X_WO};
    frames[f].object_poses[0].translation().z() += 1e-3 * f;
  }
  DeviceState device;
  device.x_W_m = Eigen::Vector3d(0.001, 0.002, -0.002);
  for (const HapticMode mode : {HapticMode::kGodObject, HapticMode::kPenalty}) {
    HapticLoopOptions options = Options(mode);
    options.godobject.stiffness_N_m = 500.0;
    options.godobject.proxy_radius_m = 0.001;
    ToolState start;
    start.x_W_m = Eigen::Vector3d(0.001, 0.002, 0.02);
    ToolShape sphere;
    sphere.kind = ToolShape::Kind::kSphere;
    sphere.radius_m = 0.001;
    HapticLoop loop(MakeToolModelWithMass(sphere, 0.01), kCoupling, kGravity, start, options,
                    &block, {plate});
    // The god-object settles at once; the penalty's haptic tool (ζ 0.25, ω 400 rad/s) within
    // tens of ms: each world is held that long.
    const int hold = mode == HapticMode::kGodObject ? kStepsPerFrame : 300;
    for (int k = 0; k < 2 * hold; ++k)  // warm-up: buffers grow
      loop.Step(device, 0.0, k % hold == 0 ? &frames[(k / hold) % 2] : nullptr);
    AllocationCounter counter;
    double force_low_N = 0.0, force_high_N = 0.0;
    for (int k = 2 * hold; k < 8 * hold; ++k) {
      const int frame = (k / hold) % 2;
      const HapticLoopOutput out = loop.Step(device, 0.0, k % hold == 0 ? &frames[frame] : nullptr);
      // Settled by the end of each hold: the last step's force for that plate height.
      if (k % hold == hold - 1)
        (frame == 0 ? force_low_N : force_high_N) = out.rendered.device_force_W_N.z();
    }
    const std::int64_t allocations = counter.count();
    // The device D = h + r − z_device under the touching point: 3 or 4 mm.
    for (const double D_m : {0.003, 0.004}) {
      const double rendered_N = D_m == 0.003 ? force_low_N : force_high_N;
      if (mode == HapticMode::kGodObject) {  // k (D + ε): the proxy on the plate's offset plane
        EXPECT_NEAR(rendered_N, 500.0 * (D_m + options.godobject.surface_epsilon_m), 1e-9);
      } else {  // the springs in series: d = (k_c D + m g)/(k + k_c), felt k_c (D − d)
        const double k = options.geometric.penalty.stiffness_N_m, k_c = kCoupling.k_lin_N_m;
        const double d_m = (k_c * D_m + 0.01 * 9.81) / (k + k_c);
        EXPECT_NEAR(rendered_N, k_c * (D_m - d_m), 1e-6) << D_m;
      }
    }
    if (AllocationCounter::enabled()) {
      EXPECT_EQ(allocations, 0) << ToString(mode);
    }
  }
}

// ---------------------------------------------------------------------------------------------

TEST(TripleBuffer, SingleThreadedSemantics) {
  TripleBuffer<int> buffer;
  EXPECT_EQ(buffer.TakeNewest(), nullptr);  // nothing published yet
  *buffer.writer_slot() = 1;
  buffer.Publish();
  const int* first = buffer.TakeNewest();
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(*first, 1);
  EXPECT_EQ(buffer.TakeNewest(), nullptr);  // taken once only
  for (int value : {2, 3, 4}) {  // three publishes without a read: only the newest is kept
    *buffer.writer_slot() = value;
    buffer.Publish();
  }
  const int* newest = buffer.TakeNewest();
  ASSERT_NE(newest, nullptr);
  EXPECT_EQ(*newest, 4);
  for (int value : {5, 6}) {  // the reader's slot is never the writer's
    EXPECT_NE(buffer.writer_slot(), newest);
    *buffer.writer_slot() = value;
    buffer.Publish();
    EXPECT_EQ(*newest, 4);
  }
  const int* next = buffer.TakeNewest();
  ASSERT_NE(next, nullptr);
  EXPECT_EQ(*next, 6);
}

struct WideValue {
  std::array<std::int64_t, 64> fields{};  // 512 bytes: far wider than any atomic store
};

TEST(TripleBuffer, TwoThreadsNeverSeeATornOrOlderValue) {
  constexpr std::int64_t kValues = 200000;
  TripleBuffer<WideValue> buffer;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  std::atomic<std::int64_t> reads_so_far{0};
  std::thread writer([&] {
    for (std::int64_t c = 1; c <= kValues; ++c) {
      buffer.writer_slot()->fields.fill(c);
      buffer.Publish();
      // Halfway, wait for the reader to have taken one: on a loaded machine the writer could
      // otherwise finish before the reader thread first runs, and nothing would overlap.
      if (c == kValues / 2)
        while (reads_so_far.load() == 0 && std::chrono::steady_clock::now() < deadline)
          std::this_thread::yield();
    }
  });
  std::int64_t last = 0, reads = 0, torn = 0, not_newer = 0;
  while (last < kValues && std::chrono::steady_clock::now() < deadline) {
    const WideValue* value = buffer.TakeNewest();
    if (value == nullptr) continue;
    const std::int64_t c = value->fields[0];
    torn += std::any_of(value->fields.begin(), value->fields.end(),
                        [c](std::int64_t f) { return f != c; });
    not_newer += c <= last;  // every non-null take is a later publish
    last = std::max(last, c);
    reads_so_far.store(++reads);
  }
  writer.join();
  EXPECT_EQ(last, kValues);  // the last value published is read (finished before the deadline)
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(not_newer, 0);
  EXPECT_GT(reads, 1);
  RecordProperty("reads", std::to_string(reads));
}

// ---------------------------------------------------------------------------------------------

// The environment: a floor z ≥ z_wall of stiffness k_env, pushing the hand out of it.
struct SpringWall {
  double z_wall_m = 0.0;
  double k_N_m = 0.0;
  Eigen::Vector3d Force(const Eigen::Vector3d& x_W_m) const {
    return Eigen::Vector3d(0, 0, -k_N_m * std::min(x_W_m.z() - z_wall_m, 0.0));
  }
  double Energy(const Eigen::Vector3d& x_W_m) const {
    const double depth_m = std::min(x_W_m.z() - z_wall_m, 0.0);
    return 0.5 * k_N_m * depth_m * depth_m;
  }
};

TEST(SimulatedHand, SettlesAtTheEquilibriumOfArmAndWall) {
  const Eigen::Quaterniond I = Eigen::Quaterniond::Identity();
  const Eigen::Vector3d target_m(0, 0, -0.02);
  const HandParams hand_params;  // 0.3 kg, 300 N/m, 10 N s/m
  const SpringWall wall{0.0, 3000.0};
  // Pulled from 1 cm above the wall to 2 cm into it over a second, then held.
  SimulatedHand hand(
      ScriptedTrajectory({{0.0, Eigen::Vector3d(0, 0, 0.01), I}, {1.0, target_m, I}}), hand_params,
      kDt_s);
  DeviceState state;
  for (int k = 0; k <= 5000; ++k) {
    double age_s = kNaN;
    long sequence = -1;
    state = hand.Read(k * kDt_s, &age_s, &sequence);
    EXPECT_EQ(age_s, 0.0);
    EXPECT_EQ(sequence, k);
    hand.Write(wall.Force(state.x_W_m), Eigen::Vector3d::Zero());
  }
  const double k_arm = hand_params.k_N_m;
  const double z_eq_m = (k_arm * target_m.z() + wall.k_N_m * wall.z_wall_m) / (k_arm + wall.k_N_m);
  EXPECT_NEAR(state.x_W_m.z(), z_eq_m, 1e-6);
  EXPECT_NEAR(state.x_W_m.x(), 0.0, 1e-12);
  EXPECT_NEAR(state.x_W_m.y(), 0.0, 1e-12);
}

TEST(SimulatedHand, UndampedEnergyDoesNotDrift) {
  const Eigen::Vector3d target_m(0, 0, -0.02);
  HandParams params;
  params.mass_kg = 1.0;
  params.k_N_m = 25.0;  // ω = 5 rad/s above the wall
  params.b_N_s_m = 0.0;
  const SpringWall wall{0.0, 75.0};  // ω = 10 rad/s in it
  // Symplectic Euler conserves a modified energy; the true one oscillates by ≈ ω Δt/2 = 0.5% of
  // itself, and never drifts. (Explicit Euler would gain ~(ω Δt)² a step: ×e over 10 s.)
  constexpr double kEnergyTolerance = 0.01;
  SimulatedHand hand(ScriptedTrajectory({{0.0, target_m, Eigen::Quaterniond::Identity()}}), params,
                     kDt_s);
  double E0_J = kNaN, max_error = 0.0, max_z_m = -1.0;
  for (int k = 0; k <= 10000; ++k) {
    double age_s;
    long sequence;
    const DeviceState state = hand.Read(k * kDt_s, &age_s, &sequence);
    const Eigen::Vector3d stretch_m = state.x_W_m - target_m;
    const double E_J = 0.5 * params.mass_kg * state.v_W_m_s.squaredNorm() +
                       0.5 * params.k_N_m * stretch_m.squaredNorm() + wall.Energy(state.x_W_m);
    if (k == 0) E0_J = E_J;  // at rest on the target, 2 cm in the wall: ½ 75 0.02² J
    max_error = std::max(max_error, std::abs(E_J - E0_J) / E0_J);
    max_z_m = std::max(max_z_m, state.x_W_m.z());
    hand.Write(wall.Force(state.x_W_m), Eigen::Vector3d::Zero());
  }
  EXPECT_NEAR(E0_J, 0.5 * wall.k_N_m * 0.02 * 0.02, 1e-15);
  EXPECT_GT(max_z_m, 0.005);  // the hand bounced out of the wall and back: both springs acted
  EXPECT_LT(max_error, kEnergyTolerance);
  RecordProperty("max_relative_energy_error", std::to_string(max_error));
}

}  // namespace
}  // namespace hapsim::device
