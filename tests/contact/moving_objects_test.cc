// Rigid objects that move (contact/visual_frame.h): a plate moved by a script, and a box grabbed
// by the tool (paper 003). Checked against kinematics and statics that do not depend on the code:
// what rests on a rising plate rises with it and stays on its surface; a grabbed box keeps its
// pose relative to the tool, stays where it is let go, and carries the tool's load onto what it
// is pressed against (the coupling's pull plus the weight; Newton's third law through a body).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "contact/rigid_objects.h"
#include "contact/visual_frame.h"
#include "fem/lattice_mesher.h"
#include "fem/time_stepper.h"
#include "tests/contact/rigid_object_fixtures.h"

namespace hapsim::contact {
namespace {

using fixtures::CalcObjectForceOnBody_N;
using fixtures::FreeBlock;
using fixtures::kGravity_m_s2;
using fixtures::MakeFreeBlock;

constexpr double kDt_s = 1.0 / 60.0;
constexpr double kToolMass_kg = 0.05;
constexpr double kToolRadius_m = 0.01;

// A 20 x 20 cm plate 1 cm thick whose top face rises from z = 0 to z = rise_m between 0.5 s and
// 1.5 s (smoothstep: peak speed 1.5 rise_m / s).
RigidObject MakeRisingPlate(double rise_m) {
  RigidObject plate;
  plate.name = "plate";
  plate.shape.kind = ToolShape::Kind::kBox;
  plate.shape.half_extents_m = Eigen::Vector3d(0.1, 0.1, 0.005);
  Waypoint start, end;
  start.t_s = 0.5;
  start.x_W_m = Eigen::Vector3d(0.0, 0.0, -0.005);
  end.t_s = 1.5;
  end.x_W_m = Eigen::Vector3d(0.0, 0.0, -0.005 + rise_m);
  plate.script.emplace(std::vector<Waypoint>{start, end});
  plate.X_WO = CalcScriptedPose(plate, 0.0);
  return plate;
}

// A grabbable 2 cm cube centred at `centre_W_m`.
RigidObject MakeCube(const Eigen::Vector3d& centre_W_m) {
  RigidObject cube;
  cube.name = "cube";
  cube.shape.kind = ToolShape::Kind::kBox;
  cube.shape.half_extents_m = Eigen::Vector3d::Constant(0.01);
  cube.X_WO.translation() = centre_W_m;
  cube.grabbable = true;
  return cube;
}

RigidObject MakeFixedPlate() {
  RigidObject plate = MakeRisingPlate(0.0);
  plate.script.reset();
  return plate;
}

VisualFrameOptions MakeOptions(double k_N_m, std::vector<RigidObject> objects) {
  VisualFrameOptions options;
  options.dt_s = kDt_s;
  options.gravity_m_s2 = Eigen::Vector3d(0.0, 0.0, -kGravity_m_s2);
  options.coupling = CouplingParams{k_N_m, 5.0, 2.0, 0.02};
  options.response.solve.law = ContactLaw::kUnilateral;  // frictionless
  options.response.solve.max_iterations = 5000;
  options.rigid_objects = std::move(objects);
  return options;
}

ToolModel MakeSphereTool() {
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = kToolRadius_m;
  return MakeToolModelWithMass(sphere, kToolMass_kg);
}

// The plate's top face at time t_s, from its script alone.
double PlateTop_m(const RigidObject& plate, double t_s) {
  return CalcScriptedPose(plate, t_s).translation().z() + plate.shape.half_extents_m.z();
}

TEST(MovingObjects, ToolRestingOnARisingPlateRisesWithItOnItsSurface) {
  const double rise_m = 0.02, k_N_m = 200.0, device_z_m = kToolRadius_m - 0.005;
  const RigidObject plate = MakeRisingPlate(rise_m);
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(),
                    MakeOptions(k_N_m, {plate}));
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, kToolRadius_m);  // resting on the plate
  DeviceState device;
  device.x_W_m = Eigen::Vector3d(0.0, 0.0, device_z_m);  // 5 mm below: pressed onto it
  fem::State no_body;
  double worst_m = 0.0;            // largest |tool bottom − plate top| while the plate moves
  for (int k = 0; k < 150; ++k) {  // 2.5 s
    frame.Step(device, &no_body, &tool);
    const double t_s = (k + 1) * kDt_s;
    EXPECT_NEAR(frame.object_pose(0).translation().z(),
                CalcScriptedPose(plate, t_s).translation().z(), 1e-15);
    if (t_s > 0.25)
      worst_m =
          std::max(worst_m, std::abs(tool.x_W_m.z() - kToolRadius_m - PlateTop_m(plate, t_s)));
  }
  // At rest on the raised plate: the coupling pulls down with k (z − z_device), gravity m g.
  const double load_N = kToolMass_kg * kGravity_m_s2 + k_N_m * (tool.x_W_m.z() - device_z_m);
  std::printf("tool on a plate rising 20 mm: worst gap %.2e m; contact force %.6f N, load %.6f N\n",
              worst_m, frame.contact_force_N().z(), load_N);
  // Without the plate's velocity in its rows the tool would trail it by v Δt / β = 2.5 mm at
  // the peak speed of 30 mm/s (β = 0.2): the rows hold a moving constraint, not a chase.
  EXPECT_LE(worst_m, 1e-4);
  EXPECT_NEAR(tool.x_W_m.z(), kToolRadius_m + rise_m, 1e-4);
  EXPECT_NEAR(frame.contact_force_N().z(), load_N, 5e-3 * load_N);
}

TEST(MovingObjects, DeformableBlockOnARisingPlateRisesWithItAndKeepsItsWeightOnIt) {
  const double rise_m = 0.01;
  const FreeBlock block = MakeFreeBlock();
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.5);  // parked far above, out of the way
  VisualFrame frame(block.model, fem::FemOptions{}, block.gravity_N, MakeSphereTool(),
                    MakeOptions(2000.0, {MakeRisingPlate(rise_m)}));
  DeviceState device;
  device.x_W_m = tool.x_W_m;
  fem::State body = fem::MakeRestState(block.model);
  const double mean_z0_m =
      Eigen::Map<const Matrix3Xd>(body.x_m.data(), 3, block.model.num_nodes()).row(2).mean();
  double deepest_m = 0.0;
  for (int k = 0; k < 240; ++k) {  // 4 s: 1 s of motion, then settling
    const VisualFrameStats stats = frame.Step(device, &body, &tool);
    deepest_m = std::max(deepest_m, stats.max_object_penetration_m);
  }
  const double mean_z_m =
      Eigen::Map<const Matrix3Xd>(body.x_m.data(), 3, block.model.num_nodes()).row(2).mean();
  const double weight_N = block.mass_kg * kGravity_m_s2;
  std::printf(
      "block on a plate rising 10 mm: rose %.6f m, plate force %.6f N (m g %.6f N), "
      "deepest node %.2e m\n",
      mean_z_m - mean_z0_m, CalcObjectForceOnBody_N(frame), weight_N, deepest_m);
  EXPECT_LE(deepest_m, 1e-4);  // no node more than 0.1 mm inside, at any frame
  // It rose with the plate; its sag under its own weight is the same before and after.
  EXPECT_NEAR(mean_z_m - mean_z0_m, rise_m, 1e-4);
  EXPECT_NEAR(CalcObjectForceOnBody_N(frame), weight_N, 5e-3 * weight_N);
}

// Friction with a plate sliding under the tool: the linear contact model takes the plate's motion
// along each contact's own tangents. Linearised at a haptic tool turned by 1 µrad (which swaps
// the tangents CalcTangents picks for an axis-aligned normal), the model must barely change:
// before the fix, the visual frame's tangential offsets were applied to the swapped rows and the
// force offset pointed sideways.
TEST(MovingObjects, ALinearModelOnASlidingPlateDoesNotDependOnTheTangentsChosen) {
  RigidObject plate = MakeRisingPlate(0.0);
  Waypoint start = plate.script->waypoints().front(), end = plate.script->waypoints().back();
  end.x_W_m.x() += 0.04;  // slides 40 mm along x between 0.5 and 1.5 s
  plate.script.emplace(std::vector<Waypoint>{start, end});
  VisualFrameOptions options = MakeOptions(200.0, {plate});
  options.response.solve.law = ContactLaw::kFriction;
  options.response.solve.friction_coefficient = 0.5;
  VisualFrame upright(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(), options);
  VisualFrame turned(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(), options);
  ToolState tool_a, tool_b;
  tool_a.x_W_m = tool_b.x_W_m = Eigen::Vector3d(0.0, 0.0, kToolRadius_m);
  DeviceState device;
  device.x_W_m = Eigen::Vector3d(0.0, 0.0, kToolRadius_m - 0.005);
  fem::State no_body;
  for (int k = 0; k < 59; ++k) {  // to 0.98 s: the plate near its fastest
    upright.Step(device, &no_body, &tool_a);
    turned.Step(device, &no_body, &tool_b);
  }
  ToolState haptic_turned = tool_b;
  haptic_turned.q_WT =
      Eigen::Quaterniond(Eigen::AngleAxisd(1e-6, Eigen::Vector3d::UnitY())) * tool_b.q_WT;
  upright.Step(device, &no_body, &tool_a, &tool_a);
  turned.Step(device, &no_body, &tool_b, &haptic_turned);
  const Eigen::Vector3d a_N = upright.linear_model().F_c0_N, b_N = turned.linear_model().F_c0_N;
  std::printf(
      "linear model on a sliding plate: F_c0 (%.6f, %.6f, %.6f) N upright, "
      "(%.6f, %.6f, %.6f) N turned by 1 urad\n",
      a_N.x(), a_N.y(), a_N.z(), b_N.x(), b_N.y(), b_N.z());
  ASSERT_GT(upright.linear_model().num_contacts, 0);
  // The plate drags the tool along its own motion, +x; nothing sideways (before the fix the
  // offset pointed along y: the round-off of turning the normals by the identity had swapped the
  // tangents already).
  EXPECT_GT(a_N.x(), 0.0);
  EXPECT_LT(std::abs(a_N.y()), 1e-6 * a_N.norm());
  EXPECT_LT((a_N - b_N).norm(), 1e-4 * a_N.norm());
}

// Drives the frame for `frames` frames with the device at x_W_m and the button as given.
void Drive(VisualFrame* frame, fem::State* body, ToolState* tool, const Eigen::Vector3d& x_W_m,
           int buttons, int frames) {
  DeviceState device;
  device.x_W_m = x_W_m;
  device.buttons = buttons;
  for (int k = 0; k < frames; ++k) frame->Step(device, body, tool);
}

TEST(MovingObjects, GrabbedCubeFollowsTheToolLoadsThePlateAndStaysWhereReleased) {
  const double k_N_m = 200.0;
  const Eigen::Vector3d cube_W_m(0.0, 0.0, 0.05);
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeSphereTool(),
                    MakeOptions(k_N_m, {MakeFixedPlate(), MakeCube(cube_W_m)}));
  fem::State no_body;
  ToolState tool;
  const double touch_z_m = cube_W_m.z() + 0.01 + kToolRadius_m;  // the sphere on the cube's top
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, touch_z_m);
  // Resting on the cube, pushed 2 mm into it: selected, not grabbed (the button is up).
  Drive(&frame, &no_body, &tool, {0.0, 0.0, touch_z_m - 0.002}, 0, 30);
  EXPECT_EQ(frame.selected_object(), 1);
  EXPECT_EQ(frame.grabbed_object(), -1);
  // The button pressed: grabbed, at its pose relative to the tool then.
  Drive(&frame, &no_body, &tool, {0.0, 0.0, touch_z_m - 0.002}, 1, 1);
  ASSERT_EQ(frame.grabbed_object(), 1);
  const Eigen::Isometry3d X_TO = CalcPose(tool).inverse() * frame.object_pose(1);
  // Carried 3 cm up and 2 cm across: it keeps that pose relative to the tool, and the tool
  // makes no contact with it.
  Drive(&frame, &no_body, &tool, {0.02, 0.0, touch_z_m + 0.03}, 1, 90);
  EXPECT_NEAR(tool.x_W_m.x(), 0.02, 1e-4);
  EXPECT_TRUE((CalcPose(tool).inverse() * frame.object_pose(1)).isApprox(X_TO, 1e-12));
  for (const Contact& contact : frame.contacts()) EXPECT_NE(contact.rigid_object, 1);
  // Lowered onto the plate, 5 mm deeper than its bottom reaches: the cube stops on the plate
  // and the plate carries the tool's weight and the coupling's pull, as if the tool were that
  // cube (the grabbed cube's contacts are the tool's).
  const double tool_over_cube_m = X_TO.inverse().translation().z();  // tool centre above cube's
  const double rest_z_m = 0.01 + tool_over_cube_m;                   // cube bottom on z = 0
  Drive(&frame, &no_body, &tool, {0.02, 0.0, rest_z_m - 0.005}, 1, 180);
  const double load_N =
      kToolMass_kg * kGravity_m_s2 + k_N_m * (tool.x_W_m.z() - (rest_z_m - 0.005));
  std::printf(
      "grabbed cube pressed on the plate: tool at %.6f m (rest %.6f m), contact force "
      "%.6f N, load %.6f N\n",
      tool.x_W_m.z(), rest_z_m, frame.contact_force_N().z(), load_N);
  EXPECT_NEAR(tool.x_W_m.z(), rest_z_m, 1e-4);
  EXPECT_NEAR(frame.contact_force_N().z(), load_N, 5e-3 * load_N);
  EXPECT_NEAR(load_N, kToolMass_kg * kGravity_m_s2 + k_N_m * 0.005, 5e-3 * load_N);
  // Released and the tool lifted away: the cube stays where it was let go.
  const Eigen::Isometry3d X_WO_released = frame.object_pose(1);
  Drive(&frame, &no_body, &tool, {0.02, 0.0, 0.2}, 0, 60);
  EXPECT_EQ(frame.grabbed_object(), -1);
  EXPECT_TRUE(frame.object_pose(1).isApprox(X_WO_released, 0.0));
  EXPECT_GT(tool.x_W_m.z(), 0.15);
}

// The grabbed cube pushed onto a soft block on the plate: what the tool feels through the cube
// goes into the block and on to the plate (third law: plate force = weight + tool's force).
TEST(MovingObjects, GrabbedCubePressingABlockPassesTheToolsForceToThePlate) {
  const FreeBlock block = MakeFreeBlock();
  const Eigen::Vector3d cube_W_m(0.0, 0.0, 0.04);  // 1 cm above the block's top face
  VisualFrame frame(block.model, fem::FemOptions{}, block.gravity_N, MakeSphereTool(),
                    MakeOptions(300.0, {MakeFixedPlate(), MakeCube(cube_W_m)}));
  fem::State body = fem::MakeRestState(block.model);
  ToolState tool;
  const double touch_z_m = cube_W_m.z() + 0.01 + kToolRadius_m;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, touch_z_m);
  Drive(&frame, &body, &tool, {0.0, 0.0, touch_z_m - 0.002}, 0, 20);
  Drive(&frame, &body, &tool, {0.0, 0.0, touch_z_m - 0.002}, 1, 1);
  ASSERT_EQ(frame.grabbed_object(), 1);
  // Down by 1 cm to the block's face and 6 mm further.
  Drive(&frame, &body, &tool, {0.0, 0.0, touch_z_m - 0.016}, 1, 300);
  const double tool_force_N = frame.contact_force_N().z();
  const double weight_N = block.mass_kg * kGravity_m_s2;
  const double expected_N = weight_N + tool_force_N;
  std::printf(
      "grabbed cube on the block on the plate: tool force %.6f N, plate force %.6f N, "
      "weight + tool force %.6f N\n",
      tool_force_N, CalcObjectForceOnBody_N(frame), expected_N);
  EXPECT_GT(tool_force_N, 2.0 * weight_N);
  EXPECT_NEAR(CalcObjectForceOnBody_N(frame), expected_N, 5e-3 * expected_N);
}

}  // namespace
}  // namespace hapsim::contact
