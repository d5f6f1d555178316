// Rigid objects in the visual frame (DESIGN.md §9), against statics that do not depend on the
// code: a deformable block on a frictionless rigid plate carries its weight on the plate; a tool
// pushed onto the plate stops at its surface, the plate's force balancing the tool's weight and
// the coupling force; a tool pressing the block adds its force to the plate's (Newton's third
// law). And the contacts themselves against the analytic distances of sphere and box.
#include "contact/rigid_objects.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <vector>

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

// A 20 x 20 cm plate 1 cm thick, top face at z = 0.
RigidObject MakePlate() {
  RigidObject plate;
  plate.name = "plate";
  plate.shape.kind = ToolShape::Kind::kBox;
  plate.shape.half_extents_m = Eigen::Vector3d(0.1, 0.1, 0.005);
  plate.X_WO.translation() = Eigen::Vector3d(0.0, 0.0, -0.005);
  return plate;
}

ToolShape MakeShape(ToolShape::Kind kind) {
  ToolShape shape;
  shape.kind = kind;
  shape.radius_m = 0.01;
  shape.length_m = 0.03;
  shape.edge_radius_m = kind == ToolShape::Kind::kCylinder ? 0.002 : 0.0;
  shape.half_extents_m = Eigen::Vector3d(0.02, 0.015, 0.01);
  return shape;
}

// The height of the centre of `shape`, upright, resting on z = 0.
double RestingHeight(const ToolShape& shape) {
  switch (shape.kind) {
    case ToolShape::Kind::kSphere:
      return shape.radius_m;
    case ToolShape::Kind::kCapsule:
      return 0.5 * shape.length_m + shape.radius_m;
    case ToolShape::Kind::kCylinder:
      return 0.5 * shape.length_m;
    case ToolShape::Kind::kBox:
      return shape.half_extents_m.z();
    case ToolShape::Kind::kMesh:
      break;
  }
  return 0.0;
}

VisualFrameOptions MakeOptions(const CouplingParams& coupling) {
  VisualFrameOptions options;
  options.dt_s = 1.0 / 60.0;
  options.gravity_m_s2 = Eigen::Vector3d(0.0, 0.0, -kGravity_m_s2);
  options.coupling = coupling;
  options.response.solve.law = ContactLaw::kUnilateral;  // frictionless
  options.response.solve.max_iterations = 5000;
  options.rigid_objects = {MakePlate()};
  return options;
}

// Largest depth of a node of `body` inside the plate (≤ 0 when none is inside), m.
double CalcDeepestNodeInPlate_m(const fem::State& body) {
  const ToolDistanceField plate(MakePlate().shape);
  const Eigen::Isometry3d X_OW = MakePlate().X_WO.inverse();
  double deepest_m = 0.0;
  for (Eigen::Index n = 0; n < body.x_m.size() / 3; ++n)
    deepest_m = std::max(
        deepest_m, -plate.Calc(X_OW * Eigen::Vector3d(body.x_m.segment<3>(3 * n))).distance_m);
  return deepest_m;
}

// A tool parked far above everything, held there by its coupling.
ToolModel MakeParkedTool(ToolState* state) {
  state->x_W_m = Eigen::Vector3d(0.0, 0.0, 0.5);
  return MakeToolModelWithMass(MakeShape(ToolShape::Kind::kSphere), 0.05);
}

TEST(RigidObjects, DeformableBlockOnAFrictionlessPlateCarriesItsWeight) {
  const FreeBlock block = MakeFreeBlock();
  ToolState tool;
  const ToolModel tool_model = MakeParkedTool(&tool);
  const CouplingParams coupling{2000.0, 20.0, 2.0, 0.02};
  VisualFrame frame(block.model, fem::FemOptions{}, block.gravity_N, tool_model,
                    MakeOptions(coupling));
  DeviceState device;
  device.x_W_m = tool.x_W_m;
  fem::State body = fem::MakeRestState(block.model);
  for (int k = 0; k < 180; ++k) frame.Step(device, &body, &tool);  // 3 s
  const double weight_N = block.mass_kg * kGravity_m_s2;
  std::printf("block on the plate: plate force %.6f N, m g %.6f N, deepest node %.2e m\n",
              CalcObjectForceOnBody_N(frame), weight_N, CalcDeepestNodeInPlate_m(body));
  EXPECT_NEAR(CalcObjectForceOnBody_N(frame), weight_N, 5e-3 * weight_N);
  EXPECT_LE(CalcDeepestNodeInPlate_m(body), 1e-4);
  // Nothing touched the tool.
  EXPECT_EQ(frame.contact_force_N().norm(), 0.0);
}

// A body clamped at its base onto the plate (its bottom nodes fixed, touching the plate): a fixed
// node makes no contact row (it would be all zero: W_ii = 0, and the friction law's tangent rows
// divided 0 by 0, turning the tool's state into NaN before the fix).
TEST(RigidObjects, FixedNodesOnAnObjectMakeNoContactRows) {
  const fem::TetMesh mesh = fem::MakeBoxTetMesh({-0.02, -0.02, 0.0}, {0.02, 0.02, 0.02}, {4, 4, 2});
  fem::Material material;
  material.youngs_modulus_Pa = 50e3;
  material.poisson_ratio = 0.45;
  const fem::Model block =
      fem::MakeModel(mesh, material, fem::FindNodesInBox(mesh, {-1, -1, -1}, {1, 1, 1e-9}, 0.0));
  ToolState tool;
  const ToolModel tool_model = MakeParkedTool(&tool);
  VisualFrameOptions options = MakeOptions(CouplingParams{2000.0, 20.0, 2.0, 0.02});
  options.response.solve.law = ContactLaw::kFriction;
  options.response.solve.friction_coefficient = 0.5;
  VisualFrame frame(block, fem::FemOptions{}, fem::CalcGravityForce(block, {0, 0, -kGravity_m_s2}),
                    tool_model, options);
  DeviceState device;
  device.x_W_m = tool.x_W_m;
  fem::State body = fem::MakeRestState(block);
  for (int k = 0; k < 10; ++k) frame.Step(device, &body, &tool);
  for (const Contact& contact : frame.contacts()) {
    for (int k = 0; k < 3; ++k)
      EXPECT_TRUE(contact.nodes[k] < 0 || !block.dof_is_fixed[3 * contact.nodes[k]]);
  }
  EXPECT_TRUE(body.x_m.allFinite() && tool.x_W_m.allFinite() && frame.impulses().allFinite());
}

// The tool against the plate alone: no body, no FEM.
TEST(RigidObjects, ToolPushedOntoAPlateStopsAtItsSurfaceAndThePlateCarriesTheLoad) {
  const double mass_kg = 0.05, k_N_m = 200.0, device_depth_m = 0.005;
  for (const ToolShape::Kind kind : {ToolShape::Kind::kSphere, ToolShape::Kind::kCapsule,
                                     ToolShape::Kind::kCylinder, ToolShape::Kind::kBox}) {
    const ToolShape shape = MakeShape(kind);
    const double height_m = RestingHeight(shape);
    SCOPED_TRACE(static_cast<int>(kind));
    const CouplingParams coupling{k_N_m, 5.0, 2.0, 0.02};
    VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeToolModelWithMass(shape, mass_kg),
                      MakeOptions(coupling));
    EXPECT_FALSE(frame.has_body());
    ToolState tool;
    tool.x_W_m = Eigen::Vector3d(0.0, 0.0, height_m + 0.002);  // 2 mm above, falling onto it
    DeviceState device;
    device.x_W_m = Eigen::Vector3d(0.0, 0.0, height_m - device_depth_m);  // 5 mm below
    fem::State no_body;
    for (int k = 0; k < 180; ++k) frame.Step(device, &no_body, &tool);
    // At rest on the surface the coupling pulls with k · 5 mm, gravity with m g (statics).
    const double load_N = mass_kg * kGravity_m_s2 + k_N_m * device_depth_m;
    std::printf("tool shape %d on the plate: contact force %.6f N, load %.6f N, depth %.2e m\n",
                static_cast<int>(kind), frame.contact_force_N().z(), load_N,
                height_m - tool.x_W_m.z());
    EXPECT_NEAR(frame.contact_force_N().z(), load_N, 5e-3 * load_N);
    EXPECT_LT(frame.contact_force_N().head<2>().norm(), 1e-6 * load_N);
    // Stopped at the surface: its deepest point no more than 0.1 mm inside the plate.
    EXPECT_GE(tool.x_W_m.z() - height_m, -1e-4);
    EXPECT_LE(tool.x_W_m.z() - height_m, 1e-4);
    EXPECT_LT(tool.v_W_m_s.norm(), 1e-4);
  }
}

TEST(RigidObjects, ToolPressingTheBlockAddsItsForceToThePlates) {
  const FreeBlock block = MakeFreeBlock();
  const CouplingParams coupling{300.0, 5.0, 2.0, 0.02};
  const ToolModel tool_model = MakeToolModelWithMass(MakeShape(ToolShape::Kind::kSphere), 0.02);
  VisualFrame frame(block.model, fem::FemOptions{}, block.gravity_N, tool_model,
                    MakeOptions(coupling));
  fem::State body = fem::MakeRestState(block.model);
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.02 + 0.01);  // on the block's top face
  DeviceState device;
  device.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.02 + 0.01 - 0.006);  // 6 mm deeper
  for (int k = 0; k < 240; ++k) frame.Step(device, &body, &tool);
  const double tool_force_N = frame.contact_force_N().z();  // up, on the tool
  const double weight_N = block.mass_kg * kGravity_m_s2;
  EXPECT_GT(tool_force_N, 2.0 * weight_N);  // a load that counts beside the block's weight
  // Body at rest: plate force = its weight + the tool's push (third law).
  const double expected_N = weight_N + tool_force_N;
  std::printf("tool on the block on the plate: plate force %.6f N, weight + tool force %.6f N\n",
              CalcObjectForceOnBody_N(frame), expected_N);
  EXPECT_NEAR(CalcObjectForceOnBody_N(frame), expected_N, 5e-3 * expected_N);
  EXPECT_LE(CalcDeepestNodeInPlate_m(body), 1e-4);
}

// Each object's own friction coefficient: a sphere pressed with load N and dragged at constant
// speed across two plates side by side slides on each with the tangential force μ N of that plate
// (Coulomb), not the scene's μ.
TEST(RigidObjects, EachObjectsOwnFrictionCoefficientHoldsTheSlidingTool) {
  const double mu_scene = 0.3, mu_left = 0.1, mu_right = 0.6;
  const double mass_kg = 0.05, k_N_m = 200.0, depth_m = 0.005, speed_m_s = 0.02;
  RigidObject left = MakePlate(), right = MakePlate();
  left.shape.half_extents_m.x() = right.shape.half_extents_m.x() = 0.05;
  left.X_WO.translation().x() = -0.05;
  right.X_WO.translation().x() = 0.05;
  left.friction_coefficient = mu_left;
  right.friction_coefficient = mu_right;
  VisualFrameOptions options = MakeOptions(CouplingParams{k_N_m, 5.0, 2.0, 0.02});
  options.rigid_objects = {left, right};
  options.response.solve.law = ContactLaw::kFriction;
  options.response.solve.friction_coefficient = mu_scene;
  const ToolShape sphere = MakeShape(ToolShape::Kind::kSphere);
  VisualFrame frame(nullptr, nullptr, Eigen::VectorXd(), MakeToolModelWithMass(sphere, mass_kg),
                    options);
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(-0.09, 0.0, sphere.radius_m);
  DeviceState device;
  device.x_W_m = Eigen::Vector3d(-0.09, 0.0, sphere.radius_m - depth_m);
  fem::State no_body;
  for (int k = 0; k < 60; ++k) frame.Step(device, &no_body, &tool);  // settle, pressed
  device.v_W_m_s.x() = speed_m_s;
  const double load_N = mass_kg * kGravity_m_s2 + k_N_m * depth_m;
  for (int k = 0; k < 9 * 60; ++k) {  // 9 s: x from −90 to +90 mm
    device.x_W_m.x() += speed_m_s / 60.0;
    frame.Step(device, &no_body, &tool);
    // Sliding in steady state over the middle of each plate.
    const double x_m = tool.x_W_m.x();
    if (std::abs(std::abs(x_m) - 0.05) > 0.02) continue;
    const double mu = x_m < 0.0 ? mu_left : mu_right;
    SCOPED_TRACE(x_m);
    EXPECT_NEAR(frame.contact_force_N().z(), load_N, 5e-3 * load_N);
    EXPECT_NEAR(-frame.contact_force_N().x(), mu * frame.contact_force_N().z(), 5e-3 * mu * load_N);
    EXPECT_NEAR(tool.v_W_m_s.x(), speed_m_s, 1e-3 * speed_m_s);
  }
  std::printf("sphere dragged over plates of mu %.1f and %.1f: F_t/F_n %.4f at the end\n", mu_left,
              mu_right, -frame.contact_force_N().x() / frame.contact_force_N().z());
}

// Contacts of a sphere tool and a box object against the analytic gaps, and their orientation.
TEST(RigidObjects, ContactsHaveTheAnalyticGapsAndNormals) {
  RigidObject box;
  box.shape.kind = ToolShape::Kind::kBox;
  box.shape.half_extents_m = Eigen::Vector3d(0.05, 0.05, 0.05);
  box.X_WO.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const ToolShape sphere = MakeShape(ToolShape::Kind::kSphere);
  const RigidObjectContacts contacts({box}, sphere, 0.002);
  // The sphere's centre 11 mm over the top face: one contact, gap 1 mm, normal −z out of the tool.
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();
  X_WT.translation() = Eigen::Vector3d(0.01, -0.02, 0.05 + 0.011);
  std::vector<Contact> found;
  contacts.AddToolContacts(X_WT, X_WT, &found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].gap_m, 0.001, 1e-12);
  EXPECT_TRUE(found[0].n_W.isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
  EXPECT_NEAR((found[0].p_body_W_m - found[0].p_tool_W_m).dot(found[0].n_W), found[0].gap_m, 1e-12);
  EXPECT_TRUE(found[0].on_tool);
  EXPECT_EQ(found[0].nodes[0], -1);
  // 3 mm over it: beyond the 2 mm margin, none; swept down by 2 mm within the frame: found.
  X_WT.translation().z() = 0.05 + 0.013;
  found.clear();
  contacts.AddToolContacts(X_WT, X_WT, &found);
  EXPECT_TRUE(found.empty());
  Eigen::Isometry3d X_WT_end = X_WT;
  X_WT_end.translation().z() -= 0.002;
  contacts.AddToolContacts(X_WT, X_WT_end, &found);
  EXPECT_EQ(found.size(), 1u);
  // A body node 0.5 mm inside the box's side face (the face's normal turned by the box's 0.3 rad).
  const Eigen::Vector3d side_W = box.X_WO.linear() * Eigen::Vector3d(0.05 - 0.0005, 0.0, 0.0);
  Eigen::VectorXd x_m(6);
  x_m << side_W, 0.0, 0.0, 0.5;  // node 1 far away
  found.clear();
  contacts.AddBodyContacts({0, 1}, x_m, x_m, X_WT, X_WT, &found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_FALSE(found[0].on_tool);
  EXPECT_EQ(found[0].nodes[0], 0);
  EXPECT_NEAR(found[0].gap_m, -0.0005, 1e-12);
  EXPECT_TRUE(found[0].n_W.isApprox(box.X_WO.linear() * Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_NEAR((found[0].p_body_W_m - found[0].p_tool_W_m).dot(found[0].n_W), found[0].gap_m, 1e-12);
}

// The box object's corner against a flat box tool face: found from the object's side.
TEST(RigidObjects, ObjectCornerUnderAToolFaceIsAContact) {
  RigidObject box;
  box.shape.kind = ToolShape::Kind::kBox;
  box.shape.half_extents_m = Eigen::Vector3d(0.01, 0.01, 0.01);
  // Stood on a corner: the top corner (0, 0, √3 · 1 cm) is the highest point.
  box.X_WO.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d(1, 1, 1).normalized(),
                                                         Eigen::Vector3d::UnitZ())
                          .toRotationMatrix();
  const double top_m = std::sqrt(3.0) * 0.01;
  const ToolShape tool = MakeShape(ToolShape::Kind::kBox);  // half height 1 cm
  const RigidObjectContacts contacts({box}, tool, 0.001);
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();
  X_WT.translation() = Eigen::Vector3d(0.003, 0.002, top_m + 0.01 + 0.0005);  // 0.5 mm above
  std::vector<Contact> found;
  contacts.AddToolContacts(X_WT, X_WT, &found);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].gap_m, 0.0005, 1e-12);
  EXPECT_TRUE(found[0].n_W.isApprox(-Eigen::Vector3d::UnitZ(), 1e-12));
}

}  // namespace
}  // namespace hapsim::contact
