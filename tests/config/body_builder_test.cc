// Scene body -> model: totals against closed forms (mass ρV, gravity + load), probes against
// the point they were placed at and a rigid translation, and the mesh-dependent input errors
// at the scene line of the key.
#include "config/body_builder.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "config/scene.h"
#include "core/error.h"
#include "fem/probe.h"
#include "fem/state.h"

namespace hapsim::config {
namespace {

// Line numbers matter: the fixed box is on line 12, the second probe on line 17.
constexpr const char* kScene = R"(name: body_test
time: {dt_s: 0.01, num_steps: 1}
gravity_m_s2: [0, 0, -10]
body:
  mesh:
    box: {min_m: [0, 0, 0], max_m: [0.2, 0.1, 0.1], cells: [4, 2, 2]}
  material:
    youngs_modulus_Pa: 1.0e5
    poisson_ratio: 0.3
    density_kg_m3: 500
  # fixed box on the next line
  fixed: {min_m: [-1, -1, -1], max_m: [0.001, 1, 1]}
  loads:
    - {min_m: [0.199, -1, -1], max_m: [1, 1, 1], total_force_N: [3, 0, -2]}
  probes:
    - {name: inside, position_m: [0.123, 0.031, 0.077]}
    - {name: corner, position_m: [0.2, 0.1, 0.1]}
)";

Body MakeTestBody(const std::string& yaml) {
  const Scene scene = ParseScene(yaml, "body_test.yaml", ".");
  return MakeBody(*scene.body, scene.gravity_m_s2);
}

TEST(BodyBuilder, TotalsMatchClosedForms) {
  const Body body = MakeTestBody(kScene);
  const double mass_kg = 500.0 * 0.2 * 0.1 * 0.1;
  EXPECT_NEAR(body.model.node_mass_kg.sum(), mass_kg, 1e-12);
  Eigen::Vector3d total_N = Eigen::Vector3d::Zero();
  for (int n = 0; n < body.model.num_nodes(); ++n)
    total_N += body.external_force_N.segment<3>(3 * n);
  EXPECT_NEAR(total_N.x(), 3.0, 1e-12);
  EXPECT_NEAR(total_N.z(), -10.0 * mass_kg - 2.0, 1e-12);
  EXPECT_EQ(body.model.num_fixed_nodes(), 3 * 3);  // the x = 0 face of a 4 x 2 x 2 lattice
}

TEST(BodyBuilder, ProbesInterpolateThePointAndFollowTranslation) {
  const Body body = MakeTestBody(kScene);
  ASSERT_EQ(body.probes.size(), 2u);
  for (const BoundProbe& probe : body.probes) {
    Eigen::Vector3d p_m = Eigen::Vector3d::Zero();
    for (int a = 0; a < 4; ++a)
      p_m += probe.binding.barycentric[a] *
             body.model.mesh.rest_positions_m.col(body.model.mesh.tets(a, probe.binding.tet));
    const Eigen::Vector3d expected_m = probe.name == "inside" ? Eigen::Vector3d(0.123, 0.031, 0.077)
                                                              : Eigen::Vector3d(0.2, 0.1, 0.1);
    EXPECT_LT((p_m - expected_m).norm(), 1e-14);
    EXPECT_GE(probe.binding.barycentric.minCoeff(), -1e-9);
  }
  fem::State state = fem::MakeRestState(body.model);
  const Eigen::Vector3d shift_m(0.01, -0.02, 0.005);
  for (int n = 0; n < body.model.num_nodes(); ++n) state.x_m.segment<3>(3 * n) += shift_m;
  EXPECT_LT(
      (fem::CalcProbeDisplacement(body.model, state, body.probes[0].binding) - shift_m).norm(),
      1e-15);
}

void ExpectErrorAt(const std::string& yaml, int line, const std::string& key) {
  try {
    MakeTestBody(yaml);
    FAIL() << "expected an InputError at line " << line;
  } catch (const InputError& error) {
    EXPECT_EQ(error.line(), line) << error.what();
    EXPECT_EQ(error.key(), key) << error.what();
  }
}

TEST(BodyBuilder, EmptyFixedBoxIsAnErrorAtItsLine) {
  std::string yaml = kScene;
  yaml.replace(yaml.find("max_m: [0.001, 1, 1]"), 20, "max_m: [-0.5, 1, 1] ");
  ExpectErrorAt(yaml, 12, "body.fixed");
}

TEST(BodyBuilder, ProbeOutsideTheBodyIsAnErrorAtItsLine) {
  std::string yaml = kScene;
  yaml.replace(yaml.find("[0.2, 0.1, 0.1]}"), 15, "[0.3, 0.1, 0.1]");
  ExpectErrorAt(yaml, 17, "body.probes[1]");
}

// element: p2 (issue 27): the same scene as quadratic tets. The fixed box holds the edge nodes on
// the x = 0 face too (counted here from the mesh), the totals are the same closed forms, and the
// probes move with a rigid translation.
TEST(BodyBuilder, QuadraticTetsKeepTheTotalsAndTheProbes) {
  std::string yaml = kScene;
  yaml.replace(yaml.find("  mesh:"), 7, "  element: p2\n  mesh:");
  const Body body = MakeTestBody(yaml);
  ASSERT_TRUE(body.model.is_quadratic());
  const double mass_kg = 500.0 * 0.2 * 0.1 * 0.1;
  EXPECT_NEAR(body.model.node_mass_kg.sum(), mass_kg, 1e-12);
  Eigen::Vector3d total_N = Eigen::Vector3d::Zero();
  for (int n = 0; n < body.model.num_nodes(); ++n)
    total_N += body.external_force_N.segment<3>(3 * n);
  EXPECT_NEAR(total_N.z(), -10.0 * mass_kg - 2.0, 1e-12);
  int on_clamped_face = 0;
  for (int n = 0; n < body.model.num_nodes(); ++n)
    on_clamped_face += body.model.mesh.rest_positions_m(0, n) < 1e-9;
  EXPECT_EQ(body.model.num_fixed_nodes(), on_clamped_face);
  EXPECT_GT(on_clamped_face, 9);  // more than the linear face's 3 × 3 corners
  fem::State state;
  state.x_m = body.model.rest_positions_m;
  for (int n = 0; n < body.model.num_nodes(); ++n)
    state.x_m.segment<3>(3 * n) += Eigen::Vector3d(0.01, -0.02, 0.03);
  for (const BoundProbe& probe : body.probes)
    EXPECT_LT((fem::CalcProbeDisplacement(body.model, state, probe.binding) -
               Eigen::Vector3d(0.01, -0.02, 0.03))
                  .norm(),
              1e-12);
}

// Quadratic tets carry embedded surfaces (fem/surface_embedding.h, tested there); a surface that
// lies outside their mesh (the liver, 16 cm long, on a 20 cm block placed elsewhere) is refused at
// its line as it is on linear tets.
TEST(BodyBuilder, QuadraticTetsRefuseASurfaceOutsideTheirMeshAtItsLine) {
  for (const char* element : {"p1", "p2"}) {
    std::string yaml = kScene;
    yaml.replace(yaml.find("  mesh:"), 7,
                 std::string("  element: ") + element +
                     "\n  visual: {file: scenes/meshes/liver.obj}\n  mesh:");
    ExpectErrorAt(yaml, 6, "body.visual");
  }
}

// Two deformable objects that start inside each other (scenes/organs.yaml with the upper organ
// lowered 2 mm into the lower): an error at the later object's entry naming both and the depth,
// 1.50 mm (the upper's bottom 1.5 mm below the lower's top, and the lower's top as far inside the
// upper: either may be named first); as shipped, 0.5 mm apart, they build.
TEST(MakeSceneBody, ObjectsStartingInsideEachOtherAreRefused) {
  std::ifstream file("scenes/organs.yaml");
  ASSERT_TRUE(file.good()) << "run from the repository root";
  std::stringstream text;
  text << file.rdbuf();
  EXPECT_TRUE(MakeSceneBody(ParseScene(text.str(), "organs.yaml", "scenes")).has_value());
  std::string lowered = text.str();
  const std::string apart = "min_m: [-0.02, -0.015, 0.0255], max_m: [0.02, 0.015, 0.0405]";
  ASSERT_NE(lowered.find(apart), std::string::npos);
  lowered.replace(lowered.find(apart), apart.size(),
                  "min_m: [-0.02, -0.015, 0.0235], max_m: [0.02, 0.015, 0.0385]");
  const Scene scene = ParseScene(lowered, "organs.yaml", "scenes");
  try {
    MakeSceneBody(scene);
    ADD_FAILURE() << "built without error";
  } catch (const InputError& error) {
    EXPECT_EQ(error.key(), "objects[1].deformable");
    const std::string what = error.what();
    EXPECT_TRUE(
        what.find("'upper_organ' and 'lower_organ' start interpenetrating") != std::string::npos ||
        what.find("'lower_organ' and 'upper_organ' start interpenetrating") != std::string::npos)
        << what;
    EXPECT_NE(what.find("1.50 mm"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace hapsim::config
