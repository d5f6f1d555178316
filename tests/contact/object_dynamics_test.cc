// Rigid objects that fall (contact/object_dynamics.h), checked against mechanics that does not
// depend on the code: free fall against backward Euler's closed form; a cube dropped tilted onto
// a plate settles flat on its surface with its energy falling, and the plate carries m g; on a
// soft block, the block carries the cube's weight and the plate both; a cube pushed across a
// frictionless plate takes the tool's push as momentum (Newton's third law); on an incline it
// stays below the friction angle and slides above it with g (sin θ − μ cos θ); let go by the
// tool, it falls.
#include "contact/object_dynamics.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "contact/visual_frame.h"
#include "tests/contact/rigid_object_fixtures.h"

namespace hapsim::contact {
namespace {

using fixtures::CalcObjectForceOnBody_N;
using fixtures::FreeBlock;
using fixtures::kGravity_m_s2;
using fixtures::MakeFreeBlock;

constexpr double kDt_s = 1.0 / 60.0;
constexpr double kCubeMass_kg = 0.05;
constexpr double kCubeHalf_m = 0.01;
const Eigen::Vector3d kGravity(0.0, 0.0, -kGravity_m_s2);

// A fixed plate 1 cm thick (20 x 20 cm unless given), its top face at z = 0 (through the origin),
// turned by `tilt_rad` about y.
RigidObject MakePlate(double tilt_rad = 0.0, double half_width_m = 0.1) {
  RigidObject plate;
  plate.name = "plate";
  plate.shape.kind = ToolShape::Kind::kBox;
  plate.shape.half_extents_m = Eigen::Vector3d(half_width_m, half_width_m, 0.005);
  plate.X_WO.linear() = Eigen::AngleAxisd(tilt_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  plate.X_WO.translation() = plate.X_WO.linear() * Eigen::Vector3d(0.0, 0.0, -0.005);
  return plate;
}

// A dynamic 2 cm cube of 50 g at X_WO, its inertia that of a uniform cube (core/rigid_tool.h).
RigidObject MakeDynamicCube(const Eigen::Isometry3d& X_WO) {
  RigidObject cube;
  cube.name = "cube";
  cube.shape.kind = ToolShape::Kind::kBox;
  cube.shape.half_extents_m = Eigen::Vector3d::Constant(kCubeHalf_m);
  cube.X_WO = X_WO;
  cube.dynamic = true;
  cube.grabbable = true;
  const ToolModel model = MakeToolModelWithMass(cube.shape, kCubeMass_kg);
  cube.mass_kg = model.mass_kg;
  cube.inertia_O_kg_m2 = model.inertia_T_kg_m2;
  return cube;
}

Eigen::Isometry3d At(const Eigen::Vector3d& x_W_m,
                     const Eigen::AngleAxisd& rotation = Eigen::AngleAxisd::Identity()) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = rotation.toRotationMatrix();
  X.translation() = x_W_m;
  return X;
}

VisualFrameOptions MakeOptions(std::vector<RigidObject> objects) {
  VisualFrameOptions options;
  options.dt_s = kDt_s;
  options.gravity_m_s2 = kGravity;
  options.coupling = CouplingParams{300.0, 5.0, 0.5, 0.005};
  options.response.solve.law = ContactLaw::kUnilateral;  // frictionless
  options.response.solve.max_iterations = 5000;
  options.rigid_objects = std::move(objects);
  return options;
}

ToolModel MakeSphereTool() { return fixtures::MakeSphereTool(0.004, 0.02); }

// The tool parked far above, out of the way, the device where it starts.
struct ParkedTool {
  ToolState state;
  DeviceState device;
  ParkedTool() { state.x_W_m = device.x_W_m = Eigen::Vector3d(0.3, 0.3, 0.3); }
};

// Σλ over the rows between the dynamic object `object` and any other rigid object, along their
// normals, N.
double CalcObjectObjectForce_N(const VisualFrame& frame, int rows_per_contact = 1) {
  double total_N = 0.0;
  for (size_t i = 0; i < frame.contacts().size(); ++i)
    if (KindOf(frame.contacts()[i]) == ContactKind::kObjectObject)
      total_N += frame.impulses()[rows_per_contact * static_cast<Eigen::Index>(i)];
  return total_N;
}

TEST(ObjectDynamics, FreeFallFollowsBackwardEulersClosedForm) {
  const Eigen::Vector3d x0(0.0, 0.0, 0.5);
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(),
                    MakeOptions({MakeDynamicCube(At(x0))}));
  ParkedTool tool;
  fem::State no_body;
  const int n = 30;  // 0.5 s
  for (int k = 0; k < n; ++k) frame.Step(tool.device, &no_body, &tool.state);
  // v_k = k Δt g, x_n = x_0 + Δt Σ_{k=1..n} v_k = x_0 + Δt² g n (n + 1)/2.
  const ToolState& cube = frame.dynamic_objects()[0].state;
  const double z_expected_m = x0.z() - kDt_s * kDt_s * kGravity_m_s2 * n * (n + 1) / 2.0;
  EXPECT_NEAR(cube.v_W_m_s.z(), -n * kDt_s * kGravity_m_s2, 1e-12);
  EXPECT_NEAR(cube.x_W_m.z(), z_expected_m, 1e-12);
  EXPECT_NEAR(frame.object_pose(0).translation().z(), z_expected_m, 1e-12);
  // And the continuous ½ g t² to within the scheme's first-order lag, Δt g t / 2.
  const double t_s = n * kDt_s;
  EXPECT_NEAR(cube.x_W_m.z(), x0.z() - 0.5 * kGravity_m_s2 * t_s * t_s,
              0.5 * kDt_s * kGravity_m_s2 * t_s + 1e-12);
  EXPECT_EQ(frame.contacts().size(), 0u);
}

TEST(ObjectDynamics, CubeDroppedTiltedSettlesFlatOnThePlateWithItsEnergyFalling) {
  // Dropped from 20 mm, turned 0.3 rad about a horizontal axis: it lands on an edge and must
  // tip over onto a face.
  const Eigen::AngleAxisd tilt(0.3, Eigen::Vector3d(1.0, 1.0, 0.0).normalized());
  const Eigen::Vector3d x0(0.0, 0.0, 0.02 + 2.0 * kCubeHalf_m);
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(),
                    MakeOptions({MakePlate(), MakeDynamicCube(At(x0, tilt))}));
  ParkedTool tool;
  fem::State no_body;
  const DynamicObject& cube = frame.dynamic_objects()[0];
  double energy_J = CalcObjectEnergy(cube, kGravity), worst_rise_J = 0.0;
  const double drop_energy_J = kCubeMass_kg * kGravity_m_s2 * 0.02;
  for (int k = 0; k < 180; ++k) {  // 3 s
    frame.Step(tool.device, &no_body, &tool.state);
    const double now_J = CalcObjectEnergy(cube, kGravity);
    worst_rise_J = std::max(worst_rise_J, now_J - energy_J);
    energy_J = now_J;
  }
  const Eigen::Vector3d up_W = cube.state.q_WT * Eigen::Vector3d::UnitZ();
  // Flat on a face: one of its axes vertical.
  double most_vertical = 0.0;
  for (int axis = 0; axis < 3; ++axis)
    most_vertical =
        std::max(most_vertical, std::abs((cube.state.q_WT * Eigen::Vector3d::Unit(axis)).z()));
  const double bottom_m = cube.state.x_W_m.z() - kCubeHalf_m;
  const double kinetic_J = CalcKineticEnergy(cube.model, cube.state);
  std::printf(
      "cube dropped 20 mm tilted 0.3 rad: bottom %.3e m above the plate, most vertical axis "
      "%.9f (up %.3f), kinetic %.2e J; energy rose by at most %.2e J a frame (%.2e of the "
      "drop's); plate force %.6f N (m g %.6f N)\n",
      bottom_m, most_vertical, up_W.z(), kinetic_J, worst_rise_J, worst_rise_J / drop_energy_J,
      CalcObjectObjectForce_N(frame), kCubeMass_kg * kGravity_m_s2);
  EXPECT_NEAR(most_vertical, 1.0, 1e-6);
  EXPECT_NEAR(bottom_m, 0.0, 1e-4);  // on its surface, within the stabilisation's 0.1 mm
  EXPECT_LT(kinetic_J, 1e-9);
  EXPECT_LE(worst_rise_J, 1e-9 * drop_energy_J);  // no frame makes energy
  EXPECT_NEAR(CalcObjectObjectForce_N(frame), kCubeMass_kg * kGravity_m_s2,
              1e-6 * kCubeMass_kg * kGravity_m_s2);
}

// Two equal cubes dropped onto the plate one above the other, the upper one offset 3 mm: face to
// face, each corner of the upper on an edge of the lower (where a corner's normal turns sideways:
// on corners alone they fell through each other). The plate carries both, the lower cube the
// upper one, and the upper rests on the lower's top.
TEST(ObjectDynamics, TwoCubesStackOnThePlate) {
  RigidObject lower = MakeDynamicCube(At(Eigen::Vector3d(0.0, 0.0, kCubeHalf_m + 0.002)));
  RigidObject upper = MakeDynamicCube(At(Eigen::Vector3d(0.003, 0.0, 3.0 * kCubeHalf_m + 0.006)));
  upper.name = "upper";
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(),
                    MakeOptions({MakePlate(), lower, upper}));
  ParkedTool tool;
  fem::State no_body;
  for (int k = 0; k < 120; ++k) frame.Step(tool.device, &no_body, &tool.state);  // 2 s
  // Σ λ n_z over each pair's rows: a row pushes its body-side object (other_object) by +λ n and
  // its tool-side one (rigid_object, the dynamic one) by −λ n.
  double plate_N = 0.0, between_N = 0.0;
  for (size_t i = 0; i < frame.contacts().size(); ++i) {
    const Contact& c = frame.contacts()[i];
    if (KindOf(c) != ContactKind::kObjectObject) continue;
    const double lambda_N = frame.impulses()[static_cast<Eigen::Index>(i)];
    if (c.other_object == 0 || c.rigid_object == 0)
      plate_N += (c.other_object == 0 ? -1.0 : 1.0) * lambda_N * c.n_W.z();
    else
      between_N += (c.other_object == 2 ? 1.0 : -1.0) * lambda_N * c.n_W.z();  // on the upper
  }
  const double weight_N = kCubeMass_kg * kGravity_m_s2;
  const ToolState& top = frame.dynamic_objects()[1].state;
  std::printf(
      "two cubes stacked: plate carries %.6f N (2 m g %.6f N), the lower carries %.6f N (m g %.6f "
      "N); "
      "upper centre z %.6f m (%.6f on the lower's top), speed %.1e m/s\n",
      plate_N, 2.0 * weight_N, between_N, weight_N, top.x_W_m.z(), 3.0 * kCubeHalf_m,
      top.v_W_m_s.norm());
  EXPECT_NEAR(plate_N, 2.0 * weight_N, 1e-6 * weight_N);
  EXPECT_NEAR(between_N, weight_N, 1e-6 * weight_N);
  EXPECT_NEAR(top.x_W_m.z(), 3.0 * kCubeHalf_m, 1e-4);
  EXPECT_NEAR(top.x_W_m.x(), 0.003, 1e-4);
  EXPECT_LT(top.v_W_m_s.norm(), 1e-6);
}

TEST(ObjectDynamics, CubeOnASoftBlockLoadsItWithItsWeight) {
  const FreeBlock block = MakeFreeBlock();                         // 4 x 4 x 2 cm on z = 0
  const Eigen::Vector3d x0(0.0, 0.0, 0.02 + kCubeHalf_m + 0.005);  // 5 mm above its top
  VisualFrameOptions options = MakeOptions({MakePlate(), MakeDynamicCube(At(x0))});
  VisualFrame frame(block.model, fem::FemOptions{}, block.gravity_N, MakeSphereTool(), options);
  ParkedTool tool;
  fem::State body = fem::MakeRestState(block.model);
  for (int k = 0; k < 360; ++k) frame.Step(tool.device, &body, &tool.state);  // 6 s
  // The vertical forces, Σ λ n_z over the body's rows with the plate (kind 2, object 0: n out of
  // the plate, pushing the block up) and with the cube (n out of the cube, pushing the cube by
  // −λ n): the plate carries block and cube, the block carries the cube.
  double plate_N = 0.0, cube_N = 0.0;
  for (size_t i = 0; i < frame.contacts().size(); ++i) {
    const Contact& contact = frame.contacts()[i];
    if (KindOf(contact) != ContactKind::kBodyObject) continue;
    const double lambda_N = frame.impulses()[static_cast<Eigen::Index>(i)];
    (contact.rigid_object == 0 ? plate_N : cube_N) += lambda_N * contact.n_W.z();
  }
  cube_N = -cube_N;
  const double cube_weight_N = kCubeMass_kg * kGravity_m_s2;
  const double block_weight_N = block.mass_kg * kGravity_m_s2;
  const ToolState& cube = frame.dynamic_objects()[0].state;
  std::printf(
      "cube on a soft block: cube rows %.6f N (m g %.6f N), plate rows %.6f N (block + cube "
      "%.6f N); cube sank %.3e m into the block, speed %.2e m/s\n",
      cube_N, cube_weight_N, plate_N, block_weight_N + cube_weight_N,
      0.02 - (cube.x_W_m.z() - kCubeHalf_m), cube.v_W_m_s.norm());
  EXPECT_NEAR(cube_N, cube_weight_N, 1e-3 * cube_weight_N);
  EXPECT_NEAR(plate_N, block_weight_N + cube_weight_N, 1e-3 * (block_weight_N + cube_weight_N));
  EXPECT_LT(cube.v_W_m_s.norm(), 1e-4);
  EXPECT_LT(cube.x_W_m.z() - kCubeHalf_m, 0.02);  // it presses the block in
}

TEST(ObjectDynamics, ToolPushingACubeAcrossAFrictionlessPlateGivesItItsPush) {
  const Eigen::Vector3d x0(0.0, 0.0, kCubeHalf_m);  // resting on the plate
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(),
                    MakeOptions({MakePlate(), MakeDynamicCube(At(x0))}));
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(-0.03, 0.0, kCubeHalf_m);  // beside the cube, at its mid-height
  DeviceState device;
  device.x_W_m = tool.x_W_m;
  fem::State no_body;
  const DynamicObject& cube = frame.dynamic_objects()[0];
  double worst_N = 0.0, push_N = 0.0;
  for (int k = 0; k < 90; ++k) {  // the device moves +x at 40 mm/s for 1 s, then stops
    if (k < 60) device.x_W_m.x() += 0.04 * kDt_s;
    const double v0_m_s = cube.state.v_W_m_s.x();
    frame.Step(device, &no_body, &tool);
    // Third law: the cube's horizontal momentum changes by the impulse the tool takes, reversed
    // (the plate's rows are vertical and frictionless).
    const double on_cube_N = kCubeMass_kg * (cube.state.v_W_m_s.x() - v0_m_s) / kDt_s;
    worst_N = std::max(worst_N, std::abs(on_cube_N + frame.contact_force_N().x()));
    push_N = std::max(push_N, std::abs(frame.contact_force_N().x()));
  }
  std::printf(
      "tool pushing a cube on a frictionless plate: largest push %.4f N, third-law mismatch "
      "%.2e N; cube at x = %.4f m, v = %.4f m/s, z = %.6f m\n",
      push_N, worst_N, cube.state.x_W_m.x(), cube.state.v_W_m_s.x(), cube.state.x_W_m.z());
  EXPECT_GT(push_N, 0.01);
  EXPECT_LT(worst_N, 1e-9 + 1e-6 * push_N);
  EXPECT_GT(cube.state.x_W_m.x(), 0.01);                 // pushed along
  EXPECT_NEAR(cube.state.x_W_m.z(), kCubeHalf_m, 1e-4);  // still on the plate
}

// The linear contact model carries the cube's inertia to the haptic step: the tool and the cube
// it pushes along x move as one, so of a force F̂ on the tool the contact takes the cube's share,
// ∂F_c/∂F̂ = −m_c / (m_c + A_v) along x, A_v = m_t + Δt_h b + Δt_h² k the tool's step mass (a
// fixed object, a wall, would take all of it: −1).
TEST(ObjectDynamics, LinearModelFeelsThePushedCubesInertia) {
  const Eigen::Vector3d x0(0.0, 0.0, kCubeHalf_m);
  const VisualFrameOptions options = MakeOptions({MakePlate(), MakeDynamicCube(At(x0))});
  const ToolModel tool_model = MakeSphereTool();
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), tool_model, options);
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(-kCubeHalf_m - 0.004, 0.0, kCubeHalf_m);  // touching its side
  DeviceState device;
  device.x_W_m = tool.x_W_m;
  fem::State no_body;
  // Pushing with the device accelerating at 1 m/s², so that the tool keeps pushing (on the
  // frictionless plate a cube pushed at a steady speed glides ahead of the tool).
  const double x0_m = device.x_W_m.x();
  for (int k = 0; k < 20; ++k) {
    const double t_s = (k + 1) * kDt_s;
    device.x_W_m.x() = x0_m + 0.5 * t_s * t_s;
    frame.Step(device, &no_body, &tool);
  }
  const double dt_h = options.haptic_dt_s;
  const double A_v = tool_model.mass_kg + dt_h * options.coupling.b_lin_N_s_m +
                     dt_h * dt_h * options.coupling.k_lin_N_m;
  const double expected = -kCubeMass_kg / (kCubeMass_kg + A_v);
  const LinearContactModel& model = frame.linear_model();
  std::printf("linear model pushing a cube: dFc/dF_xx %.9f (-m_c/(m_c + A_v) = %.9f), %d rows\n",
              model.dFc_dF(0, 0), expected, model.num_contacts);
  ASSERT_GE(model.num_contacts, 1);
  EXPECT_NEAR(model.dFc_dF(0, 0), expected, 1e-6);
}

// Friction between objects: a cube on a plate tilted by θ with μ = 0.5 (friction angle 26.6°).
double SlideDownIncline(double tilt_rad, double mu, double duration_s) {
  const RigidObject plate = MakePlate(tilt_rad, 0.5);  // long enough to slide 0.35 m on
  const Eigen::Vector3d normal = plate.X_WO.linear() * Eigen::Vector3d::UnitZ();
  Eigen::Isometry3d X_WO = plate.X_WO;
  X_WO.translation() = normal * kCubeHalf_m;  // resting on it, aligned with it
  VisualFrameOptions options = MakeOptions({plate, MakeDynamicCube(X_WO)});
  options.response.solve.law = ContactLaw::kFriction;
  options.response.solve.friction_coefficient = mu;
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(), options);
  ParkedTool tool;
  fem::State no_body;
  const int frames = static_cast<int>(std::lround(duration_s / kDt_s));
  for (int k = 0; k < frames; ++k) frame.Step(tool.device, &no_body, &tool.state);
  const Eigen::Vector3d downhill = plate.X_WO.linear() * Eigen::Vector3d::UnitX();
  return (frame.dynamic_objects()[0].state.x_W_m - X_WO.translation()).dot(downhill);
}

TEST(ObjectDynamics, CubeOnAnInclineStaysBelowTheFrictionAngleAndSlidesAbove) {
  const double mu = 0.5, duration_s = 0.5;
  const double below_m = SlideDownIncline(20.0 * M_PI / 180.0, mu, duration_s);
  const double steep_rad = 40.0 * M_PI / 180.0;
  const double above_m = SlideDownIncline(steep_rad, mu, duration_s);
  // Sliding from rest with a = g (sin θ − μ cos θ) (+x of the turned plate points down the
  // slope for a turn about +y): backward Euler's v_k = k a Δt and s_n = a Δt² n (n + 1)/2, which
  // leads ½ a t² by a Δt t / 2 (3 % here).
  const double a_m_s2 = kGravity_m_s2 * (std::sin(steep_rad) - mu * std::cos(steep_rad));
  const double n = std::lround(duration_s / kDt_s);
  const double expected_m = a_m_s2 * kDt_s * kDt_s * n * (n + 1.0) / 2.0;
  std::printf(
      "cube on an incline, mu 0.5: 20 deg moved %.3e m; 40 deg slid %.6f m (a dt^2 n(n+1)/2 = "
      "%.6f m, a t^2/2 = %.6f m)\n",
      below_m, above_m, expected_m, 0.5 * a_m_s2 * duration_s * duration_s);
  EXPECT_LT(std::abs(below_m), 1e-5);
  EXPECT_NEAR(above_m, expected_m, 1e-3 * expected_m);
}

TEST(ObjectDynamics, GrabbedCubeFallsWhenLetGo) {
  const Eigen::Vector3d x0(0.0, 0.0, kCubeHalf_m);
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(),
                    MakeOptions({MakePlate(), MakeDynamicCube(At(x0))}));
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, 2.0 * kCubeHalf_m + 0.004);  // on its top
  DeviceState device;
  device.x_W_m = tool.x_W_m - Eigen::Vector3d(0.0, 0.0, 0.001);
  fem::State no_body;
  const DynamicObject& cube = frame.dynamic_objects()[0];
  for (int k = 0; k < 30; ++k) frame.Step(device, &no_body, &tool);  // touching: selected
  ASSERT_EQ(frame.selected_object(), 1);
  device.buttons = 1;
  for (int k = 0; k < 60; ++k) {  // grabbed, lifted 30 mm
    if (k < 30) device.x_W_m.z() += 0.001;
    frame.Step(device, &no_body, &tool);
  }
  ASSERT_EQ(frame.grabbed_object(), 1);
  const double held_z_m = frame.object_pose(1).translation().z();
  EXPECT_GT(held_z_m, x0.z() + 0.025);
  device.buttons = 0;
  frame.Step(device, &no_body, &tool);
  EXPECT_EQ(frame.grabbed_object(), -1);
  // The first frames after: free fall from rest (the tool was still).
  const int n = 4;
  for (int k = 1; k < n; ++k) frame.Step(device, &no_body, &tool);
  const double fallen_m = held_z_m - cube.state.x_W_m.z();
  const double expected_m = kDt_s * kDt_s * kGravity_m_s2 * n * (n + 1) / 2.0;
  std::printf("let go at %.4f m: fell %.6f m in %d frames (free fall %.6f m)\n", held_z_m, fallen_m,
              n, expected_m);
  EXPECT_NEAR(fallen_m, expected_m, 1e-3 * expected_m);
  for (int k = 0; k < 120; ++k) frame.Step(device, &no_body, &tool);
  EXPECT_NEAR(cube.state.x_W_m.z(), kCubeHalf_m, 1e-4);  // back on the plate
  EXPECT_LT(cube.state.v_W_m_s.norm(), 1e-3);
}

}  // namespace
}  // namespace hapsim::contact
