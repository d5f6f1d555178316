// Tests of the simulation sections of config/scene.h (tool, coupling, contact, haptic, device):
// a full simulation scene parses to the expected values; each kind of bad input throws
// InputError with the expected line and key; the checks between sections; a mesh tool read from
// disk; scenes/block_press.yaml loads and matches its description.
// Tests run with the repository root as working directory (see tests/CMakeLists.txt).

#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <string>

#include "config/scene.h"
#include "config/simulation_builder.h"
#include "core/error.h"
#include "core/scripted_trajectory.h"
#include "tests/config/scene_test_support.h"

namespace hapsim::config {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Every simulation key, no body (a rigid scene). Trailing comments number the lines.
constexpr char kSimScene[] = R"(name: sim                                     #  1
time: {dt_s: 0.02, num_steps: 10}             #  2
tool:                                         #  3
  shape:                                      #  4
    capsule: {radius_m: 0.005, length_m: 0.05}    #  5
  density_kg_m3: 2000                         #  6
  position_m: [0.01, 0.02, 0.09]              #  7
  rotation_vector_rad: [0, 1.5707963267948966, 0]   #  8
coupling: {k_lin_N_m: 2000, b_lin_N_s_m: 5, k_ang_N_m_rad: 2, b_ang_N_m_s_rad: 0.01}   #  9
contact:                                      # 10
  law: friction                               # 11
  friction_coefficient: 0.3                   # 12
  stabilization_beta: 0.5                     # 13
  restitution: 0.25                           # 14
  margin_m: 0.002                             # 15
haptic:                                       # 16
  rate_hz: 500                                # 17
  mode: coupling                              # 18
device:                                       # 19
  trajectory:                                 # 20
    - {t_s: 0.0, position_m: [0, 0, 0.09], rotation_vector_rad: [0, 0, 0.5]}   # 21
    - t_s: 1.5                                # 22
      position_m: [0.01, 0, 0.08]             # 23
    - {t_s: 2.0, position_m: [0.01, 0, 0.09]} # 24
)";

// The smallest scene with a tool: the sections that have defaults are left out.
constexpr char kMinimalToolScene[] = R"(name: minimal
time: {dt_s: 0.001, num_steps: 1}
tool: {shape: {sphere: {radius_m: 0.01}}, mass_kg: 0.1}
coupling: {k_lin_N_m: 100, b_lin_N_s_m: 0, k_ang_N_m_rad: 0, b_ang_N_m_s_rad: 0}
device: {trajectory: [{t_s: 0, position_m: [0, 0, 0]}]}
)";

constexpr char kLabel[] = "sim.yaml";
constexpr char kCapsule[] = "capsule: {radius_m: 0.005, length_m: 0.05}";

using test::BadCase;
using test::ParseError;
using test::Replace;
using test::TempFolder;

// test::ExpectError for a scene parsed as kLabel.
void ExpectSimSceneError(const std::string& yaml, int line, const std::string& key,
                         const std::string& message_part) {
  test::ExpectError(yaml, kLabel, line, key, message_part);
}

TEST(SimSceneTest, FullSimulationSceneGivesEveryValue) {
  const Scene scene = ParseScene(kSimScene, kLabel, "");
  EXPECT_FALSE(scene.body.has_value());  // a rigid scene
  ASSERT_TRUE(scene.tool.has_value());
  const ToolScene& tool = *scene.tool;
  EXPECT_EQ(tool.model.shape.kind, ToolShape::Kind::kCapsule);
  EXPECT_EQ(tool.model.shape.radius_m, 0.005);
  EXPECT_EQ(tool.model.shape.length_m, 0.05);
  const double r = 0.005;
  const double volume_m3 = kPi * r * r * 0.05 + 4.0 / 3.0 * kPi * r * r * r;
  EXPECT_NEAR(tool.model.mass_kg, 2000.0 * volume_m3, 1e-15);
  EXPECT_EQ(tool.initial_state.x_W_m, Eigen::Vector3d(0.01, 0.02, 0.09));
  const Eigen::Quaterniond quarter_turn_y(Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitY()));
  EXPECT_LT(tool.initial_state.q_WT.angularDistance(quarter_turn_y), 1e-15);
  EXPECT_EQ(tool.initial_state.v_W_m_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(tool.initial_state.L_W_kg_m2_s, Eigen::Vector3d::Zero());
  EXPECT_EQ(tool.mesh_file, "");
  EXPECT_EQ(tool.location.line, 3);
  EXPECT_EQ(tool.location.key, "tool");

  EXPECT_EQ(scene.coupling.k_lin_N_m, 2000.0);
  EXPECT_EQ(scene.coupling.b_lin_N_s_m, 5.0);
  EXPECT_EQ(scene.coupling.k_ang_N_m_rad, 2.0);
  EXPECT_EQ(scene.coupling.b_ang_N_m_s_rad, 0.01);

  EXPECT_EQ(scene.contact.law, ContactLaw::kFriction);
  EXPECT_EQ(scene.contact.friction_coefficient, 0.3);
  EXPECT_EQ(scene.contact.stabilization_beta, 0.5);
  EXPECT_EQ(scene.contact.restitution, 0.25);
  EXPECT_EQ(scene.contact.margin_m, 0.002);

  EXPECT_EQ(scene.haptic.rate_hz, 500.0);
  EXPECT_EQ(scene.haptic.mode, HapticMode::kCoupling);
  EXPECT_EQ(scene.haptic.steps_per_frame, 10);

  ASSERT_EQ(scene.trajectory.size(), 3u);
  EXPECT_EQ(scene.trajectory[0].t_s, 0.0);
  EXPECT_EQ(scene.trajectory[0].x_W_m, Eigen::Vector3d(0, 0, 0.09));
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  EXPECT_LT(scene.trajectory[0].q_WD.angularDistance(yaw), 1e-15);
  EXPECT_EQ(scene.trajectory[1].t_s, 1.5);
  EXPECT_EQ(scene.trajectory[1].x_W_m, Eigen::Vector3d(0.01, 0, 0.08));
  EXPECT_EQ(scene.trajectory[1].q_WD.coeffs(), Eigen::Quaterniond::Identity().coeffs());
  EXPECT_EQ(scene.trajectory[2].t_s, 2.0);
  // What the loader accepts, the trajectory accepts.
  EXPECT_EQ(ScriptedTrajectory(scene.trajectory).duration_s(), 2.0);
}

TEST(SimSceneTest, OptionalSectionsTakeDefaults) {
  const Scene scene = ParseScene(kMinimalToolScene, kLabel, "");
  ASSERT_TRUE(scene.tool.has_value());
  EXPECT_EQ(scene.tool->model.shape.kind, ToolShape::Kind::kSphere);
  EXPECT_EQ(scene.tool->model.mass_kg, 0.1);
  EXPECT_EQ(scene.tool->initial_state.x_W_m, Eigen::Vector3d::Zero());
  EXPECT_EQ(scene.tool->initial_state.q_WT.coeffs(), Eigen::Quaterniond::Identity().coeffs());
  const ContactScene contact;
  EXPECT_EQ(scene.contact.law, ContactLaw::kUnilateral);
  EXPECT_EQ(scene.contact.friction_coefficient, contact.friction_coefficient);
  EXPECT_EQ(scene.contact.stabilization_beta, 0.2);
  EXPECT_EQ(scene.contact.restitution, 0.0);
  EXPECT_EQ(scene.contact.margin_m, 1e-3);
  EXPECT_EQ(scene.haptic.rate_hz, 1000.0);
  EXPECT_EQ(scene.haptic.mode, HapticMode::kHybrid);  // issue 25: the default holds a fast tool
  EXPECT_EQ(scene.contact.model_compliance_step, contact::ModelComplianceStep::kAuto);
  EXPECT_TRUE(scene.contact.tool_features);
  EXPECT_TRUE(MakeVisualFrameOptions(scene).detection.feature_contacts);
  EXPECT_TRUE(MakeVisualFrameOptions(scene).detection.edge_contacts);
  EXPECT_EQ(scene.haptic.steps_per_frame, 1);
  ASSERT_EQ(scene.trajectory.size(), 1u);
}

TEST(SimSceneTest, SceneWithoutToolHasNoSimulationSections) {
  const Scene scene = ParseScene("name: bare\ntime: {dt_s: 0.01, num_steps: 1}\n", kLabel, "");
  EXPECT_FALSE(scene.tool.has_value());
  EXPECT_TRUE(scene.trajectory.empty());
  EXPECT_EQ(scene.haptic.steps_per_frame, 0);
}

TEST(SimSceneTest, EnumNamesRoundTrip) {
  for (const ContactLaw law :
       {ContactLaw::kEquality, ContactLaw::kUnilateral, ContactLaw::kFriction}) {
    EXPECT_EQ(ParseContactLaw(ToString(law)), law);
  }
  for (const HapticMode mode :
       {HapticMode::kLinear, HapticMode::kLcp, HapticMode::kCoupling, HapticMode::kReference,
        HapticMode::kPenalty, HapticMode::kMaterial, HapticMode::kImpact, HapticMode::kGodObject}) {
    EXPECT_EQ(ParseHapticMode(ToString(mode)), mode);
  }
  EXPECT_EQ(ParseHapticMode("Linear"), std::nullopt);
  EXPECT_EQ(ParseContactLaw(""), std::nullopt);
}

const BadCase kBadCases[] = {
    // tool
    {"UnknownToolKey", "density_kg_m3: 2000", "densty_kg_m3: 2000", 6, "tool.densty_kg_m3",
     "allowed keys here: shape, mass_kg, density_kg_m3"},
    {"NoShape", kCapsule, "{}", 4, "tool.shape", "exactly one of sphere, capsule, cylinder"},
    {"TwoShapes", kCapsule, "sphere: {radius_m: 0.01}\n    cylinder: {radius_m: 1, length_m: 1}", 4,
     "tool.shape", "got 2"},
    {"UnknownShape", kCapsule, "cone: {radius_m: 0.01}", 5, "tool.shape.cone",
     "allowed keys here: sphere, capsule, cylinder, box, mesh"},
    {"UnknownCapsuleKey", "length_m: 0.05", "height_m: 0.05", 5, "tool.shape.capsule.height_m",
     "radius_m, length_m"},
    {"ZeroCapsuleRadius", "radius_m: 0.005", "radius_m: 0", 5, "tool.shape.capsule.radius_m",
     "must be > 0"},
    {"NegativeCapsuleLength", "length_m: 0.05", "length_m: -0.05", 5, "tool.shape.capsule.length_m",
     "must be >= 0"},
    {"ZeroSphereRadius", kCapsule, "sphere: {radius_m: 0}", 5, "tool.shape.sphere.radius_m",
     "must be > 0"},
    {"ZeroCylinderLength", kCapsule, "cylinder: {radius_m: 0.01, length_m: 0}", 5,
     "tool.shape.cylinder.length_m", "must be > 0"},
    {"MissingCylinderRadius", kCapsule, "cylinder: {length_m: 0.04}", 5,
     "tool.shape.cylinder.radius_m", "missing"},
    {"NegativeBoxExtent", kCapsule, "box: {half_extents_m: [0.01, -0.01, 0.02]}", 5,
     "tool.shape.box.half_extents_m", "element 2 must be > 0"},
    {"MissingToolMesh", kCapsule, "mesh: {file: no_such_probe.stl}", 5, "tool.shape.mesh.file",
     "no such file"},
    {"ToolMeshExtension", kCapsule, "mesh: {file: probe.msh}", 5, "tool.shape.mesh.file",
     ".obj or an .stl"},
    {"BothMassAndDensity", "density_kg_m3: 2000", "density_kg_m3: 2000\n  mass_kg: 0.1", 3, "tool",
     "exactly one of mass_kg, density_kg_m3; got 2"},
    {"NoMass", "density_kg_m3: 2000", "", 3, "tool", "got 0"},
    {"ZeroMass", "density_kg_m3: 2000", "mass_kg: 0", 6, "tool.mass_kg", "must be > 0"},
    {"NegativeDensity", "density_kg_m3: 2000", "density_kg_m3: -1", 6, "tool.density_kg_m3",
     "must be > 0"},
    {"NanToolPosition", "[0.01, 0.02, 0.09]", "[0.01, .nan, 0.09]", 7, "tool.position_m", "finite"},
    {"ShortRotationVector", "[0, 1.5707963267948966, 0]", "[0, 1]", 8, "tool.rotation_vector_rad",
     "list of 3 numbers"},
    {"EdgeRadiusAboveRadius", "capsule: {radius_m: 0.005, length_m: 0.05}",
     "cylinder: {radius_m: 0.005, length_m: 0.05, edge_radius_m: 0.006}", 5,
     "tool.shape.cylinder.edge_radius_m", "in [0, 0.005]"},
    // coupling
    {"ScalarForCoupling",
     "coupling: {k_lin_N_m: 2000, b_lin_N_s_m: 5, k_ang_N_m_rad: 2, b_ang_N_m_s_rad: 0.01}",
     "coupling: stiff", 9, "coupling", "must be a map"},
    {"NegativeStiffness", "k_lin_N_m: 2000", "k_lin_N_m: -1", 9, "coupling.k_lin_N_m",
     "must be >= 0"},
    {"StringDamping", "b_ang_N_m_s_rad: 0.01", "b_ang_N_m_s_rad: low", 9,
     "coupling.b_ang_N_m_s_rad", "must be a number"},
    {"MissingCouplingKey", ", b_ang_N_m_s_rad: 0.01", "", 9, "coupling.b_ang_N_m_s_rad", "missing"},
    {"UnknownCouplingKey", "k_ang_N_m_rad:", "k_rot_N_m_rad:", 9, "coupling.k_rot_N_m_rad",
     "allowed keys here: k_lin_N_m"},
    // contact
    {"UnknownLaw", "law: friction", "law: sticky", 11, "contact.law",
     "one of: equality, unilateral, friction"},
    {"FrictionCoefficientWithoutFriction", "law: friction", "law: unilateral", 12,
     "contact.friction_coefficient", "only with law: friction"},
    {"MissingFrictionCoefficient", "friction_coefficient: 0.3", "", 10,
     "contact.friction_coefficient", "missing"},
    {"NegativeFriction", "friction_coefficient: 0.3", "friction_coefficient: -0.1", 12,
     "contact.friction_coefficient", "must be >= 0"},
    {"BetaAboveOne", "stabilization_beta: 0.5", "stabilization_beta: 1.5", 13,
     "contact.stabilization_beta", "in [0, 1]"},
    {"NegativeRestitution", "restitution: 0.25", "restitution: -0.25", 14, "contact.restitution",
     "in [0, 1]"},
    {"NegativeMargin", "margin_m: 0.002", "margin_m: -0.001", 15, "contact.margin_m",
     "must be >= 0"},
    {"UnknownContactKey", "margin_m:", "margin:", 15, "contact.margin",
     "allowed keys here: law, friction_coefficient"},
    {"UnknownCompliance", "margin_m: 0.002", "margin_m: 0.002\n  compliance: cached", 16,
     "contact.compliance", "one of: warped, exact"},
    {"ToolFeaturesNotABool", "margin_m: 0.002", "margin_m: 0.002\n  tool_features: no", 16,
     "contact.tool_features", "one of: true, false"},
    {"UnknownModelComplianceStep", "margin_m: 0.002",
     "margin_m: 0.002\n  model_compliance_step: frame", 16, "contact.model_compliance_step",
     "one of: visual, haptic, auto"},
    {"HapticStepComplianceUnusedByTheMode", "margin_m: 0.002",
     "margin_m: 0.002\n  model_compliance_step: haptic", 16, "contact.model_compliance_step",
     "which the coupling mode does not use"},
    // haptic
    {"ZeroRate", "rate_hz: 500", "rate_hz: 0", 17, "haptic.rate_hz", "must be > 0"},
    {"FractionalStepsPerFrame", "rate_hz: 500", "rate_hz: 1000.5", 17, "haptic.rate_hz",
     "20.01 haptic steps per visual frame; it must be a whole number >= 1"},
    {"LessThanOneStepPerFrame", "rate_hz: 500", "rate_hz: 10", 17, "haptic.rate_hz",
     "0.2 haptic steps per visual frame"},
    {"UnknownMode", "mode: coupling", "mode: spring", 18, "haptic.mode",
     "one of: hybrid, linear, lcp, coupling, reference, penalty, material, impact, "
     "godobject"},
    {"GodObjectNeedsAPoint", "mode: coupling", "mode: godobject", 18, "haptic.mode",
     "renders a 3-DOF point: give tool.shape.point"},
    {"PointToolOnly", kCapsule, "point: {radius_m: 0.001}\n    sphere: {radius_m: 0.01}", 6,
     "tool.shape.sphere", "allowed keys here: point"},
    {"DynamicAboveStaticFriction", "mode: coupling",
     "mode: coupling\n  godobject: {static_friction: 0.2, dynamic_friction: 0.3}", 19,
     "haptic.godobject.dynamic_friction", "must be <= static_friction"},
    {"ZeroPenaltyStiffness", "mode: coupling", "mode: penalty\n  penalty: {stiffness_N_m: 0}", 19,
     "haptic.penalty.stiffness_N_m", "must be > 0"},
    {"UnknownPenaltyKey", "mode: coupling", "mode: penalty\n  penalty: {k: 600}", 19,
     "haptic.penalty.k", "allowed keys here: stiffness_N_m, predictive_margin"},
    {"RestitutionAboveOne", "mode: coupling", "mode: impact\n  impact: {restitution: 1.5}", 19,
     "haptic.impact.restitution", "must be in [0, 1]"},
    {"MaterialStiffnessAboveOne", "mode: coupling",
     "mode: material\n  material: {tool: {stiffness: 2}}", 19, "haptic.material.tool.stiffness",
     "must be in [0, 1]"},
    {"UnknownHapticKey", "mode: coupling", "mode: coupling\n  period_s: 0.001", 19,
     "haptic.period_s", "allowed keys here: rate_hz, mode, lcp_max_rows, lcp_friction_sweeps"},
    {"NegativeForceLimit", "mode: coupling", "mode: coupling\n  safety: {max_force_N: -1}", 19,
     "haptic.safety.max_force_N", "must be > 0"},
    {"UnknownSafetyKey", "mode: coupling", "mode: coupling\n  safety: {max_speed: 1}", 19,
     "haptic.safety.max_speed", "allowed keys here: max_force_N"},
    {"ZeroFrictionSweeps", "mode: coupling", "mode: lcp\n  lcp_friction_sweeps: 0", 19,
     "haptic.lcp_friction_sweeps", "must be >= 1"},
    {"NegativeLcpReach", "mode: coupling", "mode: lcp\n  lcp_reach_m_s: -0.01", 19,
     "haptic.lcp_reach_m_s", "must be >= 0"},
    {"ZeroLcpRows", "mode: coupling", "mode: coupling\n  lcp_max_rows: 0", 19,
     "haptic.lcp_max_rows", "must be >= 1"},
    {"LcpRowsBelowOneFrictionContact", "mode: coupling", "mode: lcp\n  lcp_max_rows: 2", 19,
     "haptic.lcp_max_rows", "2 rows hold no contact of the friction law (3 rows each): at least 3"},
    // 24 · 4 · 2e9² bytes: beyond any machine's memory (the limit printed is this machine's).
    {"LcpRowsBeyondMemory", "mode: coupling", "mode: hybrid\n  lcp_max_rows: 2000000000", 19,
     "haptic.lcp_max_rows",
     "2000000000 rows need 3.58e+11 GiB in the haptic process's four solvers"},
    // device
    {"UnknownDeviceKey", "  trajectory:", "  trajectories:", 20, "device.trajectories",
     "allowed keys here: trajectory"},
    {"TimeNotIncreasing", "t_s: 1.5", "t_s: 0.0", 22, "device.trajectory[1].t_s",
     "must be later than the waypoint before it (t_s 0 on line 21)"},
    {"EqualLastTime", "{t_s: 2.0,", "{t_s: 1.5,", 24, "device.trajectory[2].t_s",
     "must be later than the waypoint before it (t_s 1.5 on line 22)"},
    {"NegativeTime", "{t_s: 0.0,", "{t_s: -0.1,", 21, "device.trajectory[0].t_s", "must be >= 0"},
    {"MissingWaypointPosition", "      position_m: [0.01, 0, 0.08]", "", 22,
     "device.trajectory[1].position_m", "missing"},
    {"MissingWaypointTime", "{t_s: 2.0, ", "{", 24, "device.trajectory[2].t_s", "missing"},
    {"UnknownWaypointKey", "rotation_vector_rad: [0, 0, 0.5]", "rotation_rad: [0, 0, 0.5]", 21,
     "device.trajectory[0].rotation_rad", "t_s, position_m, rotation_vector_rad"},
    {"ScalarWaypoint", "{t_s: 2.0, position_m: [0.01, 0, 0.09]}", "2.0", 24, "device.trajectory[2]",
     "must be a map"},
    // the document root
    {"UnknownTopKey", "haptic:", "haptics:", 16, "haptics",
     "allowed keys here: name, description, gravity_m_s2, time, body, objects, tool, coupling, "
     "contact, haptic, device"},
};

class SimSceneBadInputTest : public testing::TestWithParam<BadCase> {};

TEST_P(SimSceneBadInputTest, ThrowsAtLineAndKey) {
  const BadCase& c = GetParam();
  ExpectSimSceneError(Replace(kSimScene, c.find, c.replace), c.line, c.key, c.message_part);
}

INSTANTIATE_TEST_SUITE_P(Cases, SimSceneBadInputTest, testing::ValuesIn(kBadCases),
                         [](const testing::TestParamInfo<BadCase>& info) {
                           return std::string(info.param.name);
                         });

// The lines of kSimScene from `first` to `last` (1-based, inclusive) left out.
std::string WithoutLines(int first, int last) {
  std::string kept;
  std::size_t start = 0;
  for (int line = 1; start < std::string(kSimScene).size(); ++line) {
    const std::size_t end = std::string(kSimScene).find('\n', start) + 1;
    if (line < first || line > last) kept += std::string(kSimScene).substr(start, end - start);
    start = end;
  }
  return kept;
}

// A mode given on the command line is held to the same rule as the scene's: the haptic-step
// compliance only where the linear contact model is rendered.
TEST(SimSceneTest, HapticStepComplianceOnlyWithTheLinearModelsModes) {
  const std::string yaml =
      std::string(kMinimalToolScene) + "contact: {model_compliance_step: haptic}\n";
  const Scene scene = ParseScene(yaml, kLabel, "");
  for (const char* mode : {"", "linear", "lcp", "reference"})
    EXPECT_NO_THROW(ResolveHapticMode(scene, mode, "--mode", /*allow_reference=*/true)) << mode;
  for (const char* mode : {"coupling", "penalty", "material", "impact"}) {
    try {
      ResolveHapticMode(scene, mode, "--mode", /*allow_reference=*/true);
      ADD_FAILURE() << "--mode " << mode << " was accepted with the haptic-step compliance";
    } catch (const InputError& error) {
      EXPECT_EQ(error.key(), "contact.model_compliance_step") << mode;
      EXPECT_NE(std::string(error.what()).find(std::string("the ") + mode + " mode does not use"),
                std::string::npos)
          << error.what();
    }
  }
}

// tool_features: false leaves the detector the body's nodes alone (node-to-surface contact): the
// feature and edge stages are both off; the margin is the scene's still.
TEST(SimSceneTest, ToolFeaturesOffTurnsOffTheFeatureAndEdgeStages) {
  const Scene scene = ParseScene(
      Replace(kSimScene, "margin_m: 0.002", "margin_m: 0.002\n  tool_features: false"), kLabel, "");
  EXPECT_FALSE(scene.contact.tool_features);
  const contact::VisualFrameOptions options = MakeVisualFrameOptions(scene);
  EXPECT_FALSE(options.detection.feature_contacts);
  EXPECT_FALSE(options.detection.edge_contacts);
  EXPECT_EQ(options.detection.margin_m, 0.002);
}

// lcp with the friction law (issue 13): accepted, the sweeps read and handed to the haptic side;
// the sweeps key without the friction law is an error naming it.
TEST(SimSceneTest, LcpTakesTheFrictionLawAndItsSweeps) {
  const Scene scene = ParseScene(
      Replace(kSimScene, "mode: coupling", "mode: lcp\n  lcp_friction_sweeps: 7"), kLabel, "");
  EXPECT_EQ(scene.haptic.mode, HapticMode::kLcp);
  EXPECT_EQ(scene.haptic.lcp_friction_sweeps, 7);
  EXPECT_EQ(ResolveHapticMode(scene, "", "--mode", false), HapticMode::kLcp);
  EXPECT_EQ(MakeMultirateOptions(scene, HapticMode::kLcp, 10).lcp_friction_sweeps, 7);
  EXPECT_EQ(MakeVisualFrameOptions(scene).lcp_reach_m_s, 0.005);  // the default
  const Scene unilateral = ParseScene(kMinimalToolScene, kLabel, "");
  EXPECT_EQ(LcpFrictionSweeps(unilateral), 0);
  try {
    ParseScene(std::string(kMinimalToolScene) + "haptic: {mode: lcp, lcp_friction_sweeps: 5}\n",
               kLabel, "");
    ADD_FAILURE() << "lcp_friction_sweeps accepted without the friction law";
  } catch (const InputError& error) {
    EXPECT_EQ(error.key(), "haptic.lcp_friction_sweeps");
    EXPECT_NE(std::string(error.what()).find("contact.law: friction"), std::string::npos);
  }
}

TEST(SimSceneTest, ToolNeedsCouplingAndDevice) {
  // A missing top-level key is reported at the document start (line 1), naming the tool's line.
  ExpectSimSceneError(WithoutLines(9, 9), 1, "coupling", "missing required key: the tool (line 3)");
  ExpectSimSceneError(WithoutLines(19, 24), 1, "device", "missing required key: the tool (line 3)");
  ExpectSimSceneError(Replace(WithoutLines(21, 24), "  trajectory:", "  trajectory: []"), 20,
                      "device.trajectory", "at least one waypoint");
  ExpectSimSceneError(WithoutLines(20, 24) + "  {}\n", 19, "device.trajectory",
                      "missing required key");
}

TEST(SimSceneTest, SectionsWithoutToolAreErrors) {
  // Without lines 3-8, the coupling line 9 becomes line 3, contact 4, haptic 10, device 13.
  const std::string no_tool = WithoutLines(3, 8);
  ExpectSimSceneError(no_tool, 3, "coupling", "applies only to a scene with a tool");
  const std::string bare = "name: bare\ntime: {dt_s: 0.01, num_steps: 1}\n";
  ExpectSimSceneError(bare + "contact: {law: equality}\n", 3, "contact", "applies only");
  ExpectSimSceneError(bare + "haptic: {rate_hz: 1000}\n", 3, "haptic", "applies only");
  ExpectSimSceneError(bare + "device: {trajectory: [{t_s: 0, position_m: [0, 0, 0]}]}\n", 3,
                      "device", "applies only");
}

TEST(SimSceneTest, DefaultHapticRateMustFitTheFrame) {
  // 1000 Hz by default: a frame of 1/60 s is 16.67 haptic steps. Reported at time.dt_s.
  const std::string yaml = Replace(kMinimalToolScene, "dt_s: 0.001", "dt_s: 0.016666666666666666");
  ExpectSimSceneError(yaml, 2, "time.dt_s", "16.6667 haptic steps per visual frame");
  ExpectSimSceneError(yaml, 2, "time.dt_s", "1000 Hz by default");
  // 600 Hz fits: 600 · 0.016666666666666666 = 10 to round-off.
  const Scene scene = ParseScene(yaml + "haptic: {rate_hz: 600}\n", kLabel, "");
  EXPECT_EQ(scene.haptic.steps_per_frame, 10);
  // A haptic section without rate_hz still reports at time.dt_s.
  ExpectSimSceneError(yaml + "haptic: {mode: coupling}\n", 2, "time.dt_s", "1000 Hz by default");
}

// A solid tetrahedron with 1 cm legs along the axes, faces outward.
constexpr char kTetrahedronObj[] = R"(v 0 0 0
v 0.01 0 0
v 0 0.01 0
v 0 0 0.01
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
)";

TEST(SimSceneTest, MeshToolIsReadAndRecentred) {
  const TempFolder folder("mesh");
  const std::string mesh_path = folder.Write("probe.OBJ", kTetrahedronObj);  // any case
  const std::string yaml = Replace(kSimScene, kCapsule, "mesh: {file: probe.OBJ}");
  const Scene scene = ParseScene(yaml, kLabel, folder.path());
  const ToolScene& tool = *scene.tool;
  EXPECT_EQ(tool.model.shape.kind, ToolShape::Kind::kMesh);
  EXPECT_EQ(tool.mesh_file, mesh_path);
  EXPECT_EQ(tool.model.shape.mesh.vertices_m.cols(), 4);
  EXPECT_EQ(tool.model.shape.mesh.triangles.cols(), 4);
  const double volume_m3 = 1e-6 / 6.0;
  EXPECT_NEAR(tool.model.mass_kg, 2000.0 * volume_m3, 1e-15);
  // The centre of mass of a solid tetrahedron is its vertex mean: now the origin of T.
  EXPECT_LT(tool.model.shape.mesh.vertices_m.rowwise().mean().norm(), 1e-15);
}

TEST(SimSceneTest, ErrorsInsideAToolMeshNameTheMeshFile) {
  const TempFolder folder("bad_mesh");
  // The last face left out: the mesh is open.
  const std::string mesh_path = folder.Write("open.obj", Replace(kTetrahedronObj, "f 2 3 4\n", ""));
  const std::string yaml = Replace(kSimScene, kCapsule, "mesh: {file: open.obj}");
  const std::optional<InputError> error = ParseError(yaml, kLabel, folder.path());
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(error->file(), mesh_path) << error->what();
  EXPECT_GT(error->line(), 0) << error->what();
}

TEST(SimSceneTest, BlockPressMatchesItsDescription) {
  const Scene scene = LoadScene("scenes/block_press.yaml");
  ASSERT_TRUE(scene.body.has_value());
  ASSERT_TRUE(scene.tool.has_value());
  const BodyScene& body = *scene.body;
  EXPECT_EQ(body.mesh.cells, Eigen::Vector3i(15, 15, 3));
  EXPECT_EQ(5 * body.mesh.cells.prod(), 3375);  // "about 3.5k tets" (issue 3)
  EXPECT_EQ(body.material.youngs_modulus_Pa, 50e3);
  EXPECT_EQ(body.material.poisson_ratio, 0.45);
  EXPECT_EQ(body.material.rayleigh_beta_s, 0.01);
  ASSERT_TRUE(body.fixed.has_value());

  const ToolScene& tool = *scene.tool;
  EXPECT_EQ(tool.model.shape.kind, ToolShape::Kind::kCylinder);
  EXPECT_EQ(tool.model.shape.radius_m, 0.02);
  EXPECT_EQ(tool.model.shape.length_m, 0.04);
  EXPECT_EQ(tool.model.mass_kg, 0.05);
  EXPECT_EQ(tool.initial_state.q_WT.coeffs(), Eigen::Quaterniond::Identity().coeffs());
  const double half_length_m = 0.5 * tool.model.shape.length_m;
  const double top_m = body.mesh.box.max_m.z();
  constexpr double kRoundOff_m = 1e-12;
  EXPECT_NEAR(tool.initial_state.x_W_m.z() - half_length_m - top_m, 0.001, kRoundOff_m);

  EXPECT_EQ(scene.coupling.k_lin_N_m, 1000.0);
  EXPECT_EQ(scene.coupling.b_lin_N_s_m, 2.0);
  EXPECT_EQ(scene.coupling.k_ang_N_m_rad, 1.0);
  EXPECT_EQ(scene.coupling.b_ang_N_m_s_rad, 0.005);
  EXPECT_EQ(scene.contact.law, ContactLaw::kUnilateral);
  EXPECT_EQ(scene.contact.stabilization_beta, 0.2);
  EXPECT_EQ(scene.contact.margin_m, 0.001);
  EXPECT_EQ(scene.haptic.rate_hz, 1000.0);
  EXPECT_EQ(scene.haptic.mode, HapticMode::kHybrid);  // the default: the scene does not say
  EXPECT_EQ(scene.haptic.steps_per_frame, 30);

  // The script: starts at the tool, presses the bottom face 4 mm below the top, slides 8 mm,
  // lifts back, and the scene runs exactly as long as the script.
  const ScriptedTrajectory script(scene.trajectory);
  EXPECT_EQ(script.Sample(0.0).x_W_m, tool.initial_state.x_W_m);
  EXPECT_EQ(script.Sample(0.2).x_W_m, tool.initial_state.x_W_m);
  EXPECT_NEAR(script.Sample(1.0).x_W_m.z() - half_length_m - top_m, -0.004, kRoundOff_m);
  EXPECT_NEAR(script.Sample(2.0).x_W_m.x(), 0.008, kRoundOff_m);
  EXPECT_NEAR(script.Sample(2.0).x_W_m.z(), script.Sample(1.0).x_W_m.z(), kRoundOff_m);
  EXPECT_EQ(script.Sample(2.8).x_W_m.z(), tool.initial_state.x_W_m.z());
  EXPECT_NEAR(scene.num_steps * scene.dt_s, script.end_time_s(), kRoundOff_m);
  // The slid tool stays on the block: its rim at x = 2 + 2.5 cm < 5 cm.
  EXPECT_LT(script.Sample(3.0).x_W_m.x() + tool.model.shape.radius_m, body.mesh.box.max_m.x());
}

}  // namespace
}  // namespace hapsim::config
