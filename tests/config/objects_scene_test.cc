// Tests of the `objects` list of config/scene.h (DESIGN.md §9): rigid and deformable entries
// parse to the expected values; a rigid-only scene has no body (builds no FEM); each kind of bad
// input throws InputError with the expected line and key; a rigid mesh object is read from disk
// and its file is named in errors.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <string>

#include "config/body_builder.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "tests/config/scene_test_support.h"

namespace hapsim::config {
namespace {

// Trailing comments number the lines.
constexpr char kObjectsScene[] = R"(name: objects                                 #  1
time: {dt_s: 0.02, num_steps: 10}             #  2
objects:                                      #  3
  - name: tray                                #  4
    rigid:                                    #  5
      shape: {box: {half_extents_m: [0.1, 0.08, 0.005]}}   #  6
      position_m: [0, 0, -0.005]              #  7
  - name: wall                                #  8
    rigid:                                    #  9
      shape: {cylinder: {radius_m: 0.02, length_m: 0.1}}   # 10
      position_m: [0.05, 0, 0.02]             # 11
      rotation_vector_rad: [1.5707963267948966, 0, 0]   # 12
  - name: organ                               # 13
    deformable:                               # 14
      mesh: {box: {min_m: [-0.02, -0.02, 0], max_m: [0.02, 0.02, 0.02], cells: [2, 2, 1]}}  # 15
      material: {youngs_modulus_Pa: 5000, poisson_ratio: 0.45, density_kg_m3: 1000}   # 16
tool: {shape: {sphere: {radius_m: 0.005}}, mass_kg: 0.02, position_m: [0, 0, 0.05]}   # 17
coupling: {k_lin_N_m: 500, b_lin_N_s_m: 2, k_ang_N_m_rad: 0, b_ang_N_m_s_rad: 0}   # 18
device: {trajectory: [{t_s: 0, position_m: [0, 0, 0.05]}]}   # 19
)";

constexpr char kLabel[] = "objects.yaml";
constexpr char kOrganLines[] =
    R"(  - name: organ                               # 13
    deformable:                               # 14
      mesh: {box: {min_m: [-0.02, -0.02, 0], max_m: [0.02, 0.02, 0.02], cells: [2, 2, 1]}}  # 15
      material: {youngs_modulus_Pa: 5000, poisson_ratio: 0.45, density_kg_m3: 1000}   # 16
)";

using test::BadCase;
using test::Replace;

TEST(ObjectsSceneTest, RigidAndDeformableObjectsParse) {
  const Scene scene = ParseScene(kObjectsScene, kLabel, "");
  ASSERT_TRUE(scene.body.has_value());
  EXPECT_EQ(scene.body_name, "organ");
  EXPECT_EQ(scene.body->material.youngs_modulus_Pa, 5000.0);
  ASSERT_EQ(scene.rigid_objects.size(), 2u);
  const contact::RigidObject& tray = scene.rigid_objects[0].object;
  EXPECT_EQ(tray.name, "tray");
  EXPECT_EQ(tray.shape.kind, ToolShape::Kind::kBox);
  EXPECT_EQ(tray.shape.half_extents_m, Eigen::Vector3d(0.1, 0.08, 0.005));
  EXPECT_TRUE(tray.X_WO.translation().isApprox(Eigen::Vector3d(0, 0, -0.005)));
  EXPECT_TRUE(tray.X_WO.linear().isIdentity());
  EXPECT_EQ(scene.rigid_objects[0].location.line, 5);
  const contact::RigidObject& wall = scene.rigid_objects[1].object;
  EXPECT_EQ(wall.shape.kind, ToolShape::Kind::kCylinder);
  // A quarter turn about x takes the cylinder's axis z to −y.
  EXPECT_TRUE((wall.X_WO.linear() * Eigen::Vector3d::UnitZ()).isApprox(-Eigen::Vector3d::UnitY()));
  // The visual frame gets them in order.
  const contact::VisualFrameOptions options = MakeVisualFrameOptions(scene);
  ASSERT_EQ(options.rigid_objects.size(), 2u);
  EXPECT_EQ(options.rigid_objects[1].name, "wall");
}

// A rigid object moved by a script starts at the script's first pose; a grabbable one is marked;
// the device's waypoints carry the button.
TEST(ObjectsSceneTest, ScriptedAndGrabbableObjectsAndTheDeviceButtonParse) {
  std::string text = Replace(kObjectsScene, "      position_m: [0, 0, -0.005]              #  7\n",
                             "      trajectory: [{t_s: 1, position_m: [0, 0, -0.005]},\n"
                             "                   {t_s: 2, position_m: [0, 0, 0.01]}]\n");
  text = Replace(text, "      position_m: [0.05, 0, 0.02]             # 11\n",
                 "      position_m: [0.05, 0, 0.02]\n      grabbable: true\n");
  text = Replace(text, "{t_s: 0, position_m: [0, 0, 0.05]}]",
                 "{t_s: 0, position_m: [0, 0, 0.05]}, {t_s: 1, position_m: [0, 0, 0.05], "
                 "button: true}, {t_s: 2, position_m: [0, 0, 0.05], button: false}]");
  const Scene scene = ParseScene(text, kLabel, "");
  const contact::RigidObject& tray = scene.rigid_objects[0].object;
  ASSERT_TRUE(tray.script.has_value());
  EXPECT_EQ(tray.script->waypoints().size(), 2u);
  EXPECT_FALSE(tray.grabbable);
  EXPECT_TRUE(tray.X_WO.translation().isApprox(Eigen::Vector3d(0, 0, -0.005)));
  EXPECT_TRUE(
      contact::CalcScriptedPose(tray, 2.5).translation().isApprox(Eigen::Vector3d(0, 0, 0.01)));
  EXPECT_TRUE(scene.rigid_objects[1].object.grabbable);
  EXPECT_FALSE(tray.friction_coefficient.has_value());
  EXPECT_FALSE(scene.rigid_objects[1].object.script.has_value());
  ASSERT_EQ(scene.trajectory.size(), 3u);
  EXPECT_EQ(scene.trajectory[0].buttons, 0);
  EXPECT_EQ(scene.trajectory[1].buttons, 1);
  EXPECT_EQ(scene.trajectory[2].buttons, 0);
}

TEST(ObjectsSceneTest, AnObjectsOwnFrictionCoefficientParsesUnderTheFrictionLaw) {
  const std::string text =
      Replace(kObjectsScene, "      position_m: [0, 0, -0.005]              #  7\n",
              "      position_m: [0, 0, -0.005]\n      friction_coefficient: 0.1\n") +
      "contact: {law: friction, friction_coefficient: 0.3}\n";
  const Scene scene = ParseScene(text, kLabel, "");
  EXPECT_EQ(scene.rigid_objects[0].object.friction_coefficient, 0.1);
  EXPECT_FALSE(scene.rigid_objects[1].object.friction_coefficient.has_value());
  EXPECT_EQ(MakeVisualFrameOptions(scene).rigid_objects[0].friction_coefficient, 0.1);
}

TEST(ObjectsSceneTest, ARigidOnlySceneHasNoBody) {
  const Scene scene = ParseScene(Replace(kObjectsScene, kOrganLines, ""), kLabel, "");
  EXPECT_FALSE(scene.body.has_value());
  EXPECT_EQ(scene.rigid_objects.size(), 2u);
}

TEST(ObjectsSceneTest, BodyIsTheShorthandForOneDeformableObject) {
  const std::string body =
      "body:\n  mesh: {box: {min_m: [0, 0, 0], max_m: [1, 1, 1], cells: [1, 1, 1]}}\n"
      "  material: {youngs_modulus_Pa: 5000, poisson_ratio: 0.45, density_kg_m3: 1000}\n";
  const Scene scene = ParseScene(Replace(kObjectsScene, kOrganLines, "") + body, kLabel, "");
  ASSERT_TRUE(scene.body.has_value());
  EXPECT_EQ(scene.body_name, "body");
  EXPECT_TRUE(scene.more_bodies.empty());
  // `body` and a deformable object: two deformable objects, `body` the first.
  const Scene two = ParseScene(std::string(kObjectsScene) + body, kLabel, "");
  EXPECT_EQ(two.body_name, "body");
  ASSERT_EQ(two.more_bodies.size(), 1u);
  EXPECT_EQ(two.more_bodies[0].name, "organ");
  EXPECT_EQ(two.more_bodies[0].body.material.youngs_modulus_Pa, 5000.0);
}

// Two free soft blocks of their own materials on a frictionless tray, solved as one system: each
// rests on the tray with its own weight ρ V g (statics; 0.5%), so each object's nodes, masses and
// contact rows are its own in the merged body.
TEST(ObjectsSceneTest, TwoDeformableObjectsOnATrayEachCarryTheirOwnWeight) {
  const Scene scene = ParseScene(R"(name: two_blocks
time: {dt_s: 0.02, num_steps: 150}
objects:
  - name: tray
    rigid: {shape: {box: {half_extents_m: [0.1, 0.1, 0.005]}}, position_m: [0, 0, -0.005]}
  - name: light
    deformable:
      mesh: {box: {min_m: [-0.05, -0.02, 0], max_m: [-0.01, 0.02, 0.02], cells: [4, 4, 2]}}
      material: {youngs_modulus_Pa: 20000, poisson_ratio: 0.45, density_kg_m3: 1000,
                 rayleigh_alpha_1_s: 5}
  - name: heavy
    deformable:
      mesh: {box: {min_m: [0.01, -0.02, 0], max_m: [0.05, 0.02, 0.02], cells: [4, 4, 2]}}
      material: {youngs_modulus_Pa: 80000, poisson_ratio: 0.45, density_kg_m3: 1500,
                 rayleigh_alpha_1_s: 5}
tool: {shape: {sphere: {radius_m: 0.01}}, mass_kg: 0.05, position_m: [0, 0, 0.5]}
coupling: {k_lin_N_m: 2000, b_lin_N_s_m: 20, k_ang_N_m_rad: 2, b_ang_N_m_s_rad: 0.02}
contact: {law: unilateral}
device: {trajectory: [{t_s: 0, position_m: [0, 0, 0.5]}]}
)",
                                 "two_blocks.yaml", "");
  const std::optional<Body> body = MakeSceneBody(scene);
  ASSERT_TRUE(body.has_value());
  const int light_nodes = 5 * 5 * 3;  // the lattice's nodes: the light block's come first
  ASSERT_EQ(body->model.num_nodes(), 2 * light_nodes);
  ASSERT_EQ(body->parts.size(), 2u);
  EXPECT_EQ(body->parts[1].first_node, light_nodes);
  EXPECT_EQ(body->parts[1].num_nodes, light_nodes);
  EXPECT_EQ(body->parts[1].first_tet, body->parts[0].num_tets);
  contact::VisualFrameOptions options = MakeVisualFrameOptions(scene);
  options.response.solve.max_iterations = 5000;
  contact::VisualFrame frame = MakeVisualFrame(scene, body, options);
  fem::State state = fem::MakeRestState(body->model);
  ToolState tool = scene.tool->initial_state;
  DeviceState device;
  device.x_W_m = tool.x_W_m;
  for (int k = 0; k < scene.num_steps; ++k) frame.Step(device, &state, &tool);
  double light_N = 0.0, heavy_N = 0.0;
  for (size_t i = 0; i < frame.contacts().size(); ++i) {
    const contact::Contact& contact = frame.contacts()[i];
    if (contact.on_tool) continue;
    (contact.nodes[0] < light_nodes ? light_N : heavy_N) +=
        frame.impulses()[static_cast<Eigen::Index>(i)];
  }
  const double volume_m3 = 0.04 * 0.04 * 0.02, g = 9.81;
  std::printf("two blocks on a tray: %.6f N (light, m g %.6f N), %.6f N (heavy, m g %.6f N)\n",
              light_N, 1000.0 * volume_m3 * g, heavy_N, 1500.0 * volume_m3 * g);
  EXPECT_NEAR(light_N, 1000.0 * volume_m3 * g, 5e-3 * 1000.0 * volume_m3 * g);
  EXPECT_NEAR(heavy_N, 1500.0 * volume_m3 * g, 5e-3 * 1500.0 * volume_m3 * g);
}

// A second deformable object joins the first one's FEM system: it may not give FEM options of
// its own, and must share the first one's damping.
TEST(ObjectsSceneTest, LaterDeformableObjectsShareTheFirstOnesSystem) {
  const std::string second =
      "  - name: second\n"
      "    deformable:\n"
      "      mesh: {box: {min_m: [0.05, -0.02, 0], max_m: [0.09, 0.02, 0.02], cells: [2, 2, 1]}}\n"
      "      material: {youngs_modulus_Pa: 50000, poisson_ratio: 0.3, density_kg_m3: 1200}\n";
  const std::string with_second = Replace(kObjectsScene, "tool: {", second + "tool: {");
  const Scene scene = ParseScene(with_second, kLabel, "");
  ASSERT_EQ(scene.more_bodies.size(), 1u);
  EXPECT_EQ(scene.more_bodies[0].body.material.youngs_modulus_Pa, 50000.0);
  test::ExpectError(Replace(with_second, "density_kg_m3: 1200}\n",
                            "density_kg_m3: 1200}\n      solver: {type: cholmod}\n"),
                    kLabel, 21, "objects[3].deformable.solver", "one system with the first one's");
  test::ExpectError(
      Replace(with_second, "density_kg_m3: 1200}", "density_kg_m3: 1200, rayleigh_alpha_1_s: 1}"),
      kLabel, 20, "objects[3].deformable.material", "share the first one's");
  test::ExpectError(Replace(with_second, "  - name: second", "  - name: organ"), kLabel, 17,
                    "objects[3].name", "duplicate object name 'organ'");
  // Probes are reported by name from the merged body: one name, one probe.
  std::string probed =
      Replace(with_second, "density_kg_m3: 1000}   # 16\n",
              "density_kg_m3: 1000}\n      probes: [{name: top, position_m: [0, 0, 0.02]}]\n");
  probed =
      Replace(probed, "density_kg_m3: 1200}\n",
              "density_kg_m3: 1200}\n      probes: [{name: top, position_m: [0.07, 0, 0.02]}]\n");
  test::ExpectError(probed, kLabel, 22, "objects[3].deformable.probes[0].name",
                    "duplicate probe name 'top' (first given on line 17)");
}

const BadCase kBadCases[] = {
    {"UnknownObjectKey", "  - name: tray", "  - nam: tray", 4, "objects[0].nam",
     "allowed keys here: name, deformable, rigid"},
    {"NoKind",
     "    rigid:                                    #  5\n      shape: {box: {half_extents_m: "
     "[0.1, 0.08, 0.005]}}   #  6\n      position_m: [0, 0, -0.005]              #  7\n",
     "", 4, "objects[0]", "exactly one of deformable, rigid"},
    {"DuplicateName", "  - name: wall", "  - name: tray", 8, "objects[1].name",
     "duplicate object name 'tray' (first given on line 4)"},
    {"EmptyName", "  - name: wall", "  - name: ''", 8, "objects[1].name", "must not be empty"},
    {"UnknownRigidKey", "      position_m: [0, 0, -0.005]", "      offset_m: [0, 0, -0.005]", 7,
     "objects[0].rigid.offset_m",
     "allowed keys here: shape, position_m, rotation_vector_rad, trajectory, grabbable, "
     "friction_coefficient"},
    {"OwnFrictionWithoutTheFrictionLaw", "      position_m: [0, 0, -0.005]              #  7\n",
     "      position_m: [0, 0, -0.005]\n      friction_coefficient: 0.2\n", 8,
     "objects[0].rigid.friction_coefficient", "needs contact.law: friction"},
    {"NegativeOwnFriction", "      position_m: [0, 0, -0.005]              #  7\n",
     "      friction_coefficient: -0.2\n", 7, "objects[0].rigid.friction_coefficient", ">= 0"},
    {"PoseAndTrajectory", "      position_m: [0, 0, -0.005]              #  7\n",
     "      position_m: [0, 0, -0.005]\n      trajectory: [{t_s: 0, position_m: [0, 0, 0]}]\n", 7,
     "objects[0].rigid.position_m", "give either a fixed pose"},
    {"ScriptedAndGrabbable", "      position_m: [0, 0, -0.005]              #  7\n",
     "      trajectory: [{t_s: 0, position_m: [0, 0, 0]}]\n      grabbable: true\n", 8,
     "objects[0].rigid.grabbable", "an object moved by a script cannot be grabbed"},
    {"GrabbableNotABool", "      position_m: [0, 0, -0.005]              #  7\n",
     "      grabbable: yes\n", 7, "objects[0].rigid.grabbable", "true, false"},
    {"ButtonOnAnObjectWaypoint", "      position_m: [0, 0, -0.005]              #  7\n",
     "      trajectory: [{t_s: 0, position_m: [0, 0, 0], button: true}]\n", 7,
     "objects[0].rigid.trajectory[0].button", "allowed keys here: t_s, position_m"},
    {"ObjectWaypointsOutOfOrder", "      position_m: [0, 0, -0.005]              #  7\n",
     "      trajectory: [{t_s: 1, position_m: [0, 0, 0]}, {t_s: 1, position_m: [0, 0, 1]}]\n", 7,
     "objects[0].rigid.trajectory[1].t_s", "must be later than the waypoint before it"},
    {"BadRigidShape", "{box: {half_extents_m: [0.1, 0.08, 0.005]}}",
     "{box: {half_extents_m: [0.1, 0, 0.005]}}", 6, "objects[0].rigid.shape.box.half_extents_m",
     "must be > 0"},
    {"NoShape", "{box: {half_extents_m: [0.1, 0.08, 0.005]}}", "{}", 6, "objects[0].rigid.shape",
     "exactly one of sphere, capsule, cylinder, box, mesh"},
    {"DynamicWithoutMass", "      position_m: [0.05, 0, 0.02]             # 11\n",
     "      position_m: [0.05, 0, 0.02]\n      dynamic: true\n", 12, "objects[1].rigid.dynamic",
     "the dynamic object wall needs its mass: give exactly one of mass_kg, density_kg_m3"},
    {"DynamicWithBothMasses", "      position_m: [0.05, 0, 0.02]             # 11\n",
     "      position_m: [0.05, 0, 0.02]\n      dynamic: true\n      mass_kg: 0.1\n"
     "      density_kg_m3: 1000\n",
     12, "objects[1].rigid.dynamic", "needs its mass: give exactly one"},
    {"MassOfAFixedObject", "      position_m: [0.05, 0, 0.02]             # 11\n",
     "      position_m: [0.05, 0, 0.02]\n      mass_kg: 0.1\n", 12, "objects[1].rigid.mass_kg",
     "only a dynamic object has a mass (dynamic: true); wall is fixed"},
    {"ZeroMass", "      position_m: [0.05, 0, 0.02]             # 11\n",
     "      position_m: [0.05, 0, 0.02]\n      dynamic: true\n      mass_kg: 0\n", 13,
     "objects[1].rigid.mass_kg", "> 0"},
    {"DynamicAndScripted", "      position_m: [0, 0, -0.005]              #  7\n",
     "      trajectory: [{t_s: 0, position_m: [0, 0, 0]}]\n      dynamic: true\n"
     "      mass_kg: 0.1\n",
     8, "objects[0].rigid.dynamic", "not by a trajectory"},
};

class ObjectsSceneBadInputTest : public testing::TestWithParam<BadCase> {};

TEST_P(ObjectsSceneBadInputTest, ThrowsAtLineAndKey) {
  const BadCase& c = GetParam();
  test::ExpectError(Replace(kObjectsScene, c.find, c.replace), kLabel, c.line, c.key,
                    c.message_part);
}

INSTANTIATE_TEST_SUITE_P(Cases, ObjectsSceneBadInputTest, testing::ValuesIn(kBadCases),
                         [](const testing::TestParamInfo<BadCase>& info) {
                           return std::string(info.param.name);
                         });

TEST(ObjectsSceneTest, RigidObjectsNeedAUnilateralLaw) {
  test::ExpectError(std::string(kObjectsScene) + "contact: {law: equality}\n", kLabel, 20,
                    "contact.law", "use unilateral or friction with rigid objects");
  EXPECT_NO_THROW(
      ParseScene(std::string(kObjectsScene) + "contact: {law: unilateral}\n", kLabel, ""));
}

TEST(ObjectsSceneTest, RigidObjectsNeedATool) {
  std::string scene = kObjectsScene;
  scene = scene.substr(0, scene.find("tool:"));
  test::ExpectError(scene, kLabel, 3, "objects", "a rigid object needs a tool");
}

TEST(ObjectsSceneTest, ADynamicObjectGetsItsMassPropertiesAndAMeshIsReCentredInPlace) {
  const std::string text =
      Replace(kObjectsScene, "      position_m: [0.05, 0, 0.02]             # 11\n",
              "      position_m: [0.05, 0, 0.02]\n      dynamic: true\n      mass_kg: 0.2\n");
  const Scene scene = ParseScene(text, kLabel, "");
  const contact::RigidObject& wall = scene.rigid_objects[1].object;
  EXPECT_TRUE(wall.dynamic);
  EXPECT_FALSE(scene.rigid_objects[0].object.dynamic);
  EXPECT_EQ(wall.mass_kg, 0.2);
  // A solid cylinder about its axis (z of O): m r² / 2; across it: m (3 r² + L²) / 12.
  const double r = 0.02, L = 0.1;
  EXPECT_NEAR(wall.inertia_O_kg_m2(2, 2), 0.2 * r * r / 2.0, 1e-3 * 0.2 * r * r / 2.0);
  EXPECT_NEAR(wall.inertia_O_kg_m2(0, 0), 0.2 * (3 * r * r + L * L) / 12.0,
              1e-3 * 0.2 * (3 * r * r + L * L) / 12.0);
  EXPECT_TRUE(MakeVisualFrameOptions(scene).rigid_objects[1].dynamic);

  // A mesh is moved so that O's origin is its centre of mass; its vertices stay where they were
  // in the world. A tetrahedron's centre of mass is the mean of its corners.
  const test::TempFolder folder("dynamic_mesh");
  folder.Write("tetra.obj",
               "v 1 0 0\nv 2 0 0\nv 1 1 0\nv 1 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  const Scene fixed =
      ParseScene(Replace(kObjectsScene, "{cylinder: {radius_m: 0.02, length_m: 0.1}}",
                         "{mesh: {file: tetra.obj}}"),
                 kLabel, folder.path());
  const Scene dynamic = ParseScene(
      Replace(text, "{cylinder: {radius_m: 0.02, length_m: 0.1}}", "{mesh: {file: tetra.obj}}"),
      kLabel, folder.path());
  const contact::RigidObject& before = fixed.rigid_objects[1].object;
  const contact::RigidObject& after = dynamic.rigid_objects[1].object;
  EXPECT_TRUE(after.shape.mesh.vertices_m.rowwise().mean().isZero(1e-12));
  for (int v = 0; v < 4; ++v)
    EXPECT_TRUE((after.X_WO * after.shape.mesh.vertices_m.col(v))
                    .isApprox(before.X_WO * before.shape.mesh.vertices_m.col(v), 1e-12));
}

// A dynamic object placed inside another object or the tissue is refused when the scene is built,
// at its entry, naming both and the depth; touching is not interpenetrating.
TEST(ObjectsSceneTest, ADynamicObjectThatStartsInsideSomethingIsRefused) {
  const auto dynamic_wall_at = [](const std::string& position) {
    return Replace(kObjectsScene, "      position_m: [0.05, 0, 0.02]             # 11\n",
                   "      position_m: " + position + "\n      dynamic: true\n      mass_kg: 0.2\n");
  };
  const auto build_error = [](const std::string& text) -> std::optional<InputError> {
    try {
      MakeSceneBody(ParseScene(text, kLabel, ""));
    } catch (const InputError& error) {
      return error;
    }
    return std::nullopt;
  };
  // Lying on the tray (its side 20 mm from its axis at z = 20 mm): touching, accepted.
  EXPECT_FALSE(build_error(dynamic_wall_at("[0.05, 0, 0.02]")).has_value());
  // 5 mm lower: 5 mm into the tray.
  const std::optional<InputError> in_tray = build_error(dynamic_wall_at("[0.05, 0, 0.015]"));
  ASSERT_TRUE(in_tray.has_value());
  EXPECT_EQ(in_tray->line(), 9);
  EXPECT_EQ(in_tray->key(), "objects[1].rigid");
  EXPECT_NE(std::string(in_tray->what())
                .find("the dynamic object 'wall' and 'tray' start interpenetrating, 5.00 mm deep"),
            std::string::npos)
      << in_tray->what();
  // Over the organ's edge: its corner nodes at (0.02, y, 0.02) lie 20 − √(15² + 10²) = 1.97 mm
  // inside the cylinder's side.
  const std::optional<InputError> in_organ = build_error(dynamic_wall_at("[0.035, 0, 0.03]"));
  ASSERT_TRUE(in_organ.has_value());
  EXPECT_NE(std::string(in_organ->what())
                .find("the dynamic object 'wall' and 'organ' start interpenetrating, 1.97 mm deep"),
            std::string::npos)
      << in_organ->what();
}

// A closed mesh object is read from its file, kept in its own frame; an open one is an error
// naming the mesh file.
TEST(ObjectsSceneTest, RigidMeshObjectIsReadInItsOwnFrame) {
  const test::TempFolder folder("rigid_mesh");
  // A unit tetrahedron away from the origin: kept there (not re-centred like a tool).
  const std::string tetra =
      "v 1 0 0\nv 2 0 0\nv 1 1 0\nv 1 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  folder.Write("tetra.obj", tetra);
  const std::string yaml = Replace(kObjectsScene, "{cylinder: {radius_m: 0.02, length_m: 0.1}}",
                                   "{mesh: {file: tetra.obj}}");
  const Scene scene = ParseScene(yaml, kLabel, folder.path());
  const contact::RigidObject& wall = scene.rigid_objects[1].object;
  EXPECT_EQ(wall.shape.kind, ToolShape::Kind::kMesh);
  EXPECT_EQ(wall.shape.mesh.vertices_m.col(0), Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(scene.rigid_objects[1].mesh_file, folder.path() + "/tetra.obj");
  // One face removed: open.
  folder.Write("tetra.obj", tetra.substr(0, tetra.rfind("f 2 3 4")));
  const std::optional<InputError> error = test::ParseError(yaml, kLabel, folder.path());
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(error->file(), folder.path() + "/tetra.obj") << error->what();
}

}  // namespace
}  // namespace hapsim::config
