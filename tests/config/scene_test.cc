// Tests of config/scene.h: a full scene parses to the expected values; each kind of bad input
// throws InputError with the expected line and key; the scenes shipped in scenes/ load.
// Tests run with the repository root as working directory (see tests/CMakeLists.txt).

#include "config/scene.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "tests/config/scene_test_support.h"

namespace hapsim::config {
namespace {

namespace fs = std::filesystem;
using test::BadCase;
using test::ExpectError;
using test::ParseError;
using test::Replace;
using test::TempFolder;

// A scene using every key; the trailing comments number the lines, so the bad-input cases below
// can name the line they break.
constexpr char kFullScene[] = R"(name: full                                    #  1
description: "a test scene"                   #  2
gravity_m_s2: [0, 0, -9.8]                    #  3
time:                                         #  4
  dt_s: 0.01                                  #  5
  num_steps: 20                               #  6
body:                                         #  7
  mesh:                                       #  8
    box: {min_m: [-0.05, -0.05, 0], max_m: [0.05, 0.05, 0.05], cells: [12, 12, 5]}   #  9
  material:                                   # 10
    youngs_modulus_Pa: 50000                  # 11
    poisson_ratio: 0.45                       # 12
    density_kg_m3: 1000                       # 13
    rayleigh_alpha_1_s: 0.1                   # 14
    rayleigh_beta_s: 0.01                     # 15
  elasticity: linear                          # 16
  integrator: explicit                        # 17
  solver: {type: cholmod, relative_tolerance: 1e-8, max_iterations: 50, factor_precision: double}   # 18
  fixed: {min_m: [-1, -1, -0.001], max_m: [1, 1, 0.001]}                  # 19
  loads:                                      # 20
    - {min_m: [-1, -1, 0.049], max_m: [1, 1, 0.051], total_force_N: [0, 0, -2]}   # 21
  probes:                                     # 22
    - {name: top_center, position_m: [0, 0, 0.05]}                        # 23
    - name: corner                            # 24
      position_m: [0.05, 0.05, 0.05]          # 25
)";

constexpr char kLabel[] = "test.yaml";
constexpr char kBoxLine[] =
    "box: {min_m: [-0.05, -0.05, 0], max_m: [0.05, 0.05, 0.05], cells: [12, 12, 5]}";

TEST(ParseSceneTest, FullSceneGivesEveryValue) {
  const Scene scene = ParseScene(kFullScene, kLabel, "");
  EXPECT_EQ(scene.file, kLabel);
  EXPECT_EQ(scene.name, "full");
  EXPECT_EQ(scene.description, "a test scene");
  EXPECT_EQ(scene.gravity_m_s2, Eigen::Vector3d(0, 0, -9.8));
  EXPECT_EQ(scene.dt_s, 0.01);
  EXPECT_EQ(scene.num_steps, 20);
  ASSERT_TRUE(scene.body.has_value());
  const BodyScene& body = *scene.body;

  EXPECT_EQ(body.mesh.kind, MeshSource::Kind::kBox);
  EXPECT_EQ(body.mesh.box.min_m, Eigen::Vector3d(-0.05, -0.05, 0));
  EXPECT_EQ(body.mesh.box.max_m, Eigen::Vector3d(0.05, 0.05, 0.05));
  EXPECT_EQ(body.mesh.cells, Eigen::Vector3i(12, 12, 5));

  EXPECT_EQ(body.material.youngs_modulus_Pa, 50000.0);
  EXPECT_EQ(body.material.poisson_ratio, 0.45);
  EXPECT_EQ(body.material.density_kg_m3, 1000.0);
  EXPECT_EQ(body.material.rayleigh_alpha_1_s, 0.1);
  EXPECT_EQ(body.material.rayleigh_beta_s, 0.01);

  EXPECT_EQ(body.options.elasticity, fem::ElasticityKind::kLinear);
  EXPECT_EQ(body.options.integrator, fem::IntegratorKind::kExplicitEuler);
  EXPECT_EQ(body.options.solver.kind, fem::SolverKind::kCholmod);
  EXPECT_EQ(body.options.solver.relative_tolerance, 1e-8);
  EXPECT_EQ(body.options.solver.max_iterations, 50);
  EXPECT_EQ(body.options.solver.factor_precision, fem::FactorPrecision::kDouble);

  ASSERT_TRUE(body.fixed.has_value());
  EXPECT_EQ(body.fixed->min_m, Eigen::Vector3d(-1, -1, -0.001));
  EXPECT_EQ(body.fixed->max_m, Eigen::Vector3d(1, 1, 0.001));

  ASSERT_EQ(body.loads.size(), 1u);
  EXPECT_EQ(body.loads[0].region.min_m, Eigen::Vector3d(-1, -1, 0.049));
  EXPECT_EQ(body.loads[0].region.max_m, Eigen::Vector3d(1, 1, 0.051));
  EXPECT_EQ(body.loads[0].total_force_N, Eigen::Vector3d(0, 0, -2));

  ASSERT_EQ(body.probes.size(), 2u);
  EXPECT_EQ(body.probes[0].name, "top_center");
  EXPECT_EQ(body.probes[0].position_m, Eigen::Vector3d(0, 0, 0.05));
  EXPECT_EQ(body.probes[1].name, "corner");
  EXPECT_EQ(body.probes[1].position_m, Eigen::Vector3d(0.05, 0.05, 0.05));
}

TEST(ParseSceneTest, SourceLocationsNameFileLineAndKey) {
  const Scene scene = ParseScene(kFullScene, kLabel, "");
  const BodyScene& body = *scene.body;
  auto expect_location = [](const SourceLocation& location, int line, const std::string& key) {
    EXPECT_EQ(location.file, kLabel);
    EXPECT_EQ(location.line, line);
    EXPECT_EQ(location.key, key);
  };
  expect_location(body.mesh.location, 8, "body.mesh");
  expect_location(body.fixed_location, 19, "body.fixed");
  expect_location(body.loads[0].location, 21, "body.loads[0]");
  expect_location(body.probes[0].location, 23, "body.probes[0]");
  expect_location(body.probes[1].location, 24, "body.probes[1]");
}

TEST(ParseSceneTest, MinimalSceneTakesDefaults) {
  const Scene scene = ParseScene("name: bare\ntime: {dt_s: 1e-3, num_steps: 1}\n", kLabel, "");
  EXPECT_EQ(scene.description, "");
  EXPECT_EQ(scene.gravity_m_s2, Eigen::Vector3d(0, 0, -9.81));
  EXPECT_EQ(scene.dt_s, 1e-3);
  EXPECT_EQ(scene.num_steps, 1);
  EXPECT_FALSE(scene.body.has_value());
}

TEST(ParseSceneTest, MinimalBodyTakesDefaults) {
  const Scene scene = ParseScene(R"(name: bare
time: {dt_s: 0.01, num_steps: 5}
body:
  mesh: {ellipsoid: {center_m: [0, 0, 0.03], radii_m: [0.06, 0.04, 0.03], cell_size_m: 0.006}}
  material: {youngs_modulus_Pa: 5e3, poisson_ratio: -0.2, density_kg_m3: 1060}
)",
                                 kLabel, "");
  const BodyScene& body = *scene.body;
  EXPECT_EQ(body.mesh.kind, MeshSource::Kind::kEllipsoid);
  EXPECT_EQ(body.mesh.center_m, Eigen::Vector3d(0, 0, 0.03));
  EXPECT_EQ(body.mesh.radii_m, Eigen::Vector3d(0.06, 0.04, 0.03));
  EXPECT_EQ(body.mesh.cell_size_m, 0.006);
  EXPECT_EQ(body.material.youngs_modulus_Pa, 5e3);
  EXPECT_EQ(body.material.poisson_ratio, -0.2);
  EXPECT_EQ(body.material.rayleigh_alpha_1_s, 0.0);
  EXPECT_EQ(body.material.rayleigh_beta_s, 0.0);
  const fem::FemOptions defaults;
  EXPECT_EQ(body.options.elasticity, defaults.elasticity);
  EXPECT_EQ(body.options.integrator, defaults.integrator);
  EXPECT_EQ(body.options.solver.kind, defaults.solver.kind);
  EXPECT_EQ(body.options.solver.relative_tolerance, defaults.solver.relative_tolerance);
  EXPECT_EQ(body.options.solver.max_iterations, defaults.solver.max_iterations);
  EXPECT_EQ(body.options.solver.factor_precision, fem::FactorPrecision::kSingle);
  EXPECT_FALSE(body.fixed.has_value());
  EXPECT_TRUE(body.loads.empty());
  EXPECT_TRUE(body.probes.empty());
}

const BadCase kBadCases[] = {
    // YAML syntax, reported at the line yaml-cpp gives.
    {"SyntaxExtraBracket", "cells: [12, 12, 5]}", "cells: [12, 12, 5]]}", 9, "", "syntax"},
    {"SyntaxTabIndent", "    poisson_ratio", "\tpoisson_ratio", 12, "", "syntax"},
    // Unknown keys, at every level, listing what is allowed.
    {"UnknownTopKey", "description:", "descripton:", 2, "descripton", "allowed keys here: name"},
    {"UnknownMaterialKey", "youngs_modulus_Pa: 50000", "youngs_modulus: 50000", 11,
     "body.material.youngs_modulus", "youngs_modulus_Pa, poisson_ratio, density_kg_m3"},
    {"UnknownProbeKey", "position_m: [0.05", "positon_m: [0.05", 25, "body.probes[1].positon_m",
     "name, position_m"},
    {"UnknownBoxKey", "cells:", "cell:", 9, "body.mesh.box.cell", "min_m, max_m, cells"},
    // Issue 9: a lattice that cannot fit in memory is refused before any allocation (it was
    // `std::bad_alloc` with no key).
    {"LatticeBeyondMemory", "cells: [12, 12, 5]", "cells: [100000, 100000, 100000]", 9,
     "body.mesh.box.cells", "does not fit in this machine's"},
    {"DuplicateKey", "rayleigh_beta_s: 0.01", "rayleigh_alpha_1_s: 0.2", 15,
     "body.material.rayleigh_alpha_1_s", "line 14"},
    // Missing required keys, at the line of the key holding the map.
    {"MissingDt", "dt_s: 0.01", "", 4, "time.dt_s", "missing"},
    {"MissingPoisson", "poisson_ratio: 0.45", "", 10, "body.material.poisson_ratio", "missing"},
    {"MissingProbePosition", "top_center, position_m: [0, 0, 0.05]", "top_center", 23,
     "body.probes[0].position_m", "missing"},
    {"MissingBoxCells", ", cells: [12, 12, 5]", "", 9, "body.mesh.box.cells", "missing"},
    // Wrong types.
    {"StringForNumber", "youngs_modulus_Pa: 50000", "youngs_modulus_Pa: soft", 11,
     "body.material.youngs_modulus_Pa", "must be a number, got 'soft'"},
    {"QuotedNumber", "density_kg_m3: 1000", "density_kg_m3: \"1000\"", 13,
     "body.material.density_kg_m3", "must be a number"},
    {"VectorOfTwo", "[0, 0, -9.8]", "[0, -9.8]", 3, "gravity_m_s2", "list of 3 numbers"},
    {"ScalarForVector", "[0, 0, -9.8]", "-9.8", 3, "gravity_m_s2", "list of 3 numbers"},
    {"FractionalCells", "cells: [12, 12, 5]", "cells: [12, 12.5, 5]", 9, "body.mesh.box.cells",
     "element 2 must be an integer"},
    {"FractionalSteps", "num_steps: 20", "num_steps: 1.5", 6, "time.num_steps",
     "must be an integer"},
    {"ExponentIterations", "max_iterations: 50", "max_iterations: 5e1", 18,
     "body.solver.max_iterations", "must be an integer"},
    {"MapForList", "    - {min_m: [-1, -1, 0.049]", "      {min_m: [-1, -1, 0.049]", 20,
     "body.loads", "must be a list"},
    {"ScalarForListItem", "{name: top_center, position_m: [0, 0, 0.05]}", "top_center", 23,
     "body.probes[0]", "must be a map"},
    {"MapForString", "elasticity: linear", "elasticity: {type: linear}", 16, "body.elasticity",
     "must be a string"},
    {"ScalarForMap",
     "solver: {type: cholmod, relative_tolerance: 1e-8, max_iterations: 50, factor_precision: "
     "double}",
     "solver: cg", 18, "body.solver", "must be a map"},
    {"NullForMap", "fixed: {min_m: [-1, -1, -0.001], max_m: [1, 1, 0.001]}", "fixed:", 19,
     "body.fixed", "got nothing"},
    // Out of range.
    {"ZeroYoungs", "youngs_modulus_Pa: 50000", "youngs_modulus_Pa: 0", 11,
     "body.material.youngs_modulus_Pa", "must be > 0"},
    {"PoissonHalf", "poisson_ratio: 0.45", "poisson_ratio: 0.5", 12, "body.material.poisson_ratio",
     "in (-1, 0.5)"},
    {"PoissonMinusOne", "poisson_ratio: 0.45", "poisson_ratio: -1", 12,
     "body.material.poisson_ratio", "in (-1, 0.5)"},
    {"NegativeDensity", "density_kg_m3: 1000", "density_kg_m3: -1000", 13,
     "body.material.density_kg_m3", "must be > 0"},
    {"NegativeAlpha", "rayleigh_alpha_1_s: 0.1", "rayleigh_alpha_1_s: -0.1", 14,
     "body.material.rayleigh_alpha_1_s", "must be >= 0"},
    {"NegativeBeta", "rayleigh_beta_s: 0.01", "rayleigh_beta_s: -1e-3", 15,
     "body.material.rayleigh_beta_s", "must be >= 0"},
    {"ZeroDt", "dt_s: 0.01", "dt_s: 0", 5, "time.dt_s", "must be > 0"},
    {"InfiniteDt", "dt_s: 0.01", "dt_s: .inf", 5, "time.dt_s", "finite"},
    {"OverflowDt", "dt_s: 0.01", "dt_s: 1e999", 5, "time.dt_s", "finite"},
    {"NanDt", "dt_s: 0.01", "dt_s: .nan", 5, "time.dt_s", "finite"},
    {"ZeroSteps", "num_steps: 20", "num_steps: 0", 6, "time.num_steps", "must be >= 1"},
    {"NanGravity", "[0, 0, -9.8]", "[0, .NaN, -9.8]", 3, "gravity_m_s2", "finite"},
    {"BoxMaxNotAboveMin", "max_m: [0.05, 0.05, 0.05]", "max_m: [0.05, -0.05, 0.05]", 9,
     "body.mesh.box.max_m", "axis y"},
    {"BoxFlat", "max_m: [0.05, 0.05, 0.05]", "max_m: [0.05, 0.05, 0]", 9, "body.mesh.box.max_m",
     "axis z"},
    {"ZeroCells", "cells: [12, 12, 5]", "cells: [12, 0, 5]", 9, "body.mesh.box.cells",
     "must be >= 1"},
    {"GradingFocusOutside", "cells: [12, 12, 5]",
     "cells: [12, 12, 5], graded: {focus_m: [0, 0, "
     "0.06], ratio: 4}",
     9, "body.mesh.box.graded.focus_m", "inside the box"},
    {"GradingRatioBelowOne", "cells: [12, 12, 5]",
     "cells: [12, 12, 5], graded: {focus_m: [0, "
     "0, 0.05], ratio: 0.5}",
     9, "body.mesh.box.graded.ratio", ">= 1"},
    {"GradingCircleZero", "cells: [12, 12, 5]",
     "cells: [12, 12, 5], graded: {focus_m: [0, 0, 0.05], ratio: 4, circle_radius_m: 0}", 9,
     "body.mesh.box.graded.circle_radius_m", "> 0"},
    {"ToleranceOne", "relative_tolerance: 1e-8", "relative_tolerance: 1", 18,
     "body.solver.relative_tolerance", "in (0, 1)"},
    {"ToleranceZero", "relative_tolerance: 1e-8", "relative_tolerance: 0", 18,
     "body.solver.relative_tolerance", "in (0, 1)"},
    {"ZeroIterations", "max_iterations: 50", "max_iterations: 0", 18, "body.solver.max_iterations",
     "must be >= 1"},
    {"FixedMaxBelowMin", "max_m: [1, 1, 0.001]", "max_m: [1, 1, -0.002]", 19, "body.fixed.max_m",
     "axis z"},
    {"LoadMaxBelowMin", "max_m: [1, 1, 0.051]", "max_m: [-2, 1, 0.051]", 21, "body.loads[0].max_m",
     "axis x"},
    {"NanLoad", "total_force_N: [0, 0, -2]", "total_force_N: [0, 0, .nan]", 21,
     "body.loads[0].total_force_N", "finite"},
    {"InfiniteProbe", "position_m: [0.05, 0.05, 0.05]", "position_m: [0.05, -.inf, 0.05]", 25,
     "body.probes[1].position_m", "finite"},
    {"DuplicateProbeName", "name: corner", "name: top_center", 24, "body.probes[1].name",
     "duplicate probe name"},
    // Unknown enum values, listing the allowed ones.
    {"UnknownElasticity", "elasticity: linear", "elasticity: neohookean", 16, "body.elasticity",
     "one of: corotational, linear"},
    {"UnknownIntegrator", "integrator: explicit", "integrator: rk4", 17, "body.integrator",
     "one of: implicit, explicit"},
    {"UnknownSolver", "type: cholmod", "type: lu", 18, "body.solver.type", "one of: cg, cholmod"},
    {"UnknownFactorPrecision", "factor_precision: double", "factor_precision: quarter", 18,
     "body.solver.factor_precision", "one of: single, double, half"},
    // Mesh sources.
    {"NoMeshSource", kBoxLine, "{}", 8, "body.mesh",
     "exactly one of box, ellipsoid, file, surface; got 0"},
    {"TwoMeshSources", "cells: [12, 12, 5]}", "cells: [12, 12, 5]}\n    file: a.msh", 8,
     "body.mesh", "got 2"},
    {"MissingMeshFile", kBoxLine, "file: no_such_mesh.msh", 9, "body.mesh.file", "no such file"},
    {"MeshFileExtension", kBoxLine, "file: liver.stl", 9, "body.mesh.file", ".msh"},
    {"ZeroEllipsoidRadius", kBoxLine,
     "ellipsoid: {center_m: [0, 0, 0], radii_m: [0.06, 0, 0.03], cell_size_m: 0.006}", 9,
     "body.mesh.ellipsoid.radii_m", "element 2 must be > 0"},
    {"EllipsoidBeyondMemory", kBoxLine,
     "ellipsoid: {center_m: [0, 0, 0], radii_m: [1, 1, 1], cell_size_m: 1e-5}", 9,
     "body.mesh.ellipsoid.cell_size_m", "does not fit in this machine's"},
    {"ZeroCellSize", kBoxLine,
     "ellipsoid: {center_m: [0, 0, 0], radii_m: [0.06, 0.04, 0.03], cell_size_m: 0}", 9,
     "body.mesh.ellipsoid.cell_size_m", "must be > 0"},
};

class SceneBadInputTest : public testing::TestWithParam<BadCase> {};

TEST_P(SceneBadInputTest, ThrowsAtLineAndKey) {
  const BadCase& c = GetParam();
  ExpectError(Replace(kFullScene, c.find, c.replace), kLabel, c.line, c.key, c.message_part);
}

INSTANTIATE_TEST_SUITE_P(Cases, SceneBadInputTest, testing::ValuesIn(kBadCases),
                         [](const testing::TestParamInfo<BadCase>& info) {
                           return std::string(info.param.name);
                         });

TEST(ParseSceneTest, MissingTopLevelKeyIsReportedAtTheDocumentStart) {
  // The document's map starts at its first key, on line 2 once line 1 is emptied.
  const std::optional<InputError> error = ParseError(Replace(kFullScene, "name: full", ""), kLabel);
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(error->line(), 2);
  EXPECT_EQ(error->key(), "name");
}

TEST(ParseSceneTest, DocumentMustBeANonEmptyMap) {
  std::optional<InputError> error = ParseError("# only a comment\n", kLabel);
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(error->line(), 0);
  error = ParseError("\n- name: a\n", kLabel);
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(error->line(), 2);
  EXPECT_EQ(error->key(), "");
}

TEST(ParseSceneTest, WhatNamesFileLineAndKey) {
  const std::optional<InputError> error =
      ParseError(Replace(kFullScene, "poisson_ratio: 0.45", "poisson_ratio: 0.7"), kLabel);
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(
      std::string(error->what()).rfind("test.yaml:12: key 'body.material.poisson_ratio': ", 0), 0u)
      << error->what();
}

TEST(ParseSceneTest, MeshFileIsResolvedAgainstBaseDir) {
  const TempFolder folder("mesh_file");
  const std::string mesh_path = folder.Write("liver.msh");
  const std::string yaml = Replace(kFullScene, kBoxLine, "file: liver.msh");
  const Scene scene = ParseScene(yaml, kLabel, folder.path());
  EXPECT_EQ(scene.body->mesh.kind, MeshSource::Kind::kFile);
  EXPECT_EQ(scene.body->mesh.file, mesh_path);
  // An absolute path is taken as is, whatever base_dir says.
  const Scene absolute =
      ParseScene(Replace(kFullScene, kBoxLine, "file: " + mesh_path), kLabel, "");
  EXPECT_EQ(absolute.body->mesh.file, mesh_path);
  // The same name relative to another folder does not exist.
  const std::optional<InputError> error = ParseError(yaml, kLabel, "/nonexistent_dir");
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(error->line(), 9);
  EXPECT_EQ(error->key(), "body.mesh.file");
}

TEST(ParseSceneTest, TetGenMeshNeedsItsEleFile) {
  const TempFolder folder("tetgen");
  folder.Write("organ.node");
  const std::string yaml = Replace(kFullScene, kBoxLine, "file: organ.node");
  const std::optional<InputError> error = ParseError(yaml, kLabel, folder.path());
  ASSERT_TRUE(error.has_value());
  EXPECT_EQ(error->line(), 9);
  EXPECT_NE(std::string(error->what()).find("organ.ele"), std::string::npos) << error->what();
  folder.Write("organ.ele");
  EXPECT_EQ(ParseScene(yaml, kLabel, folder.path()).body->mesh.kind, MeshSource::Kind::kFile);
}

TEST(LoadSceneTest, ResolvesMeshFilesAgainstTheSceneFolder) {
  const TempFolder folder("load");
  const std::string mesh_path = folder.Write("liver.msh");
  const std::string scene_path =
      folder.Write("scene.yaml", Replace(kFullScene, kBoxLine, "file: liver.msh"));
  const Scene scene = LoadScene(scene_path);
  EXPECT_EQ(scene.file, scene_path);
  EXPECT_EQ(scene.body->mesh.file, mesh_path);
  EXPECT_EQ(scene.body->mesh.location.file, scene_path);
}

TEST(LoadSceneTest, MissingOrEmptyFileErrors) {
  for (const std::string path : {"scenes/no_such_scene.yaml", "scenes"}) {
    try {
      LoadScene(path);
      ADD_FAILURE() << "no error for " << path;
    } catch (const InputError& error) {
      EXPECT_EQ(error.file(), path);
      EXPECT_EQ(error.line(), 0);
    }
  }
  const TempFolder folder("empty");
  EXPECT_THROW(LoadScene(folder.Write("empty.yaml")), InputError);
}

TEST(LoadSceneTest, EveryShippedSceneLoads) {
  int num_scenes = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator("scenes")) {
    if (entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(LoadScene(entry.path().string()));
    ++num_scenes;
  }
  EXPECT_GE(num_scenes, 4);
}

// Rest positions of the box lattice `mesh` describes: (cells + 1) nodes per axis, evenly spaced.
std::vector<Eigen::Vector3d> LatticeNodes(const MeshSource& mesh) {
  std::vector<Eigen::Vector3d> nodes;
  const Eigen::Vector3d step =
      (mesh.box.max_m - mesh.box.min_m).cwiseQuotient(mesh.cells.cast<double>());
  for (int i = 0; i <= mesh.cells.x(); ++i) {
    for (int j = 0; j <= mesh.cells.y(); ++j) {
      for (int k = 0; k <= mesh.cells.z(); ++k) {
        nodes.push_back(mesh.box.min_m + step.cwiseProduct(Eigen::Vector3d(i, j, k)));
      }
    }
  }
  return nodes;
}

// In the lattice scenes the fixed box holds exactly the nodes with coordinate `axis` = 0, and
// each probe sits on a node (to round-off: 1e-12 m is far below any cell size).
void ExpectFixedFaceAndProbesOnNodes(const std::string& path, int axis, int num_face_nodes) {
  SCOPED_TRACE(path);
  constexpr double kRoundOff_m = 1e-12;
  const Scene scene = LoadScene(path);
  ASSERT_TRUE(scene.body.has_value() && scene.body->fixed.has_value());
  const std::vector<Eigen::Vector3d> nodes = LatticeNodes(scene.body->mesh);
  int num_fixed = 0;
  for (const Eigen::Vector3d& p : nodes) {
    const bool fixed = scene.body->fixed->Contains(p, kRoundOff_m);
    EXPECT_EQ(fixed, std::abs(p[axis]) < kRoundOff_m) << p.transpose();
    num_fixed += fixed;
  }
  EXPECT_EQ(num_fixed, num_face_nodes);
  for (const Probe& probe : scene.body->probes) {
    double nearest_m = 1.0;
    for (const Eigen::Vector3d& p : nodes)
      nearest_m = std::min(nearest_m, (p - probe.position_m).norm());
    EXPECT_LT(nearest_m, kRoundOff_m) << probe.name;
  }
}

TEST(LoadSceneTest, BlockScenesMatchTheReference) {
  const Scene small = LoadScene("scenes/block_small.yaml");
  EXPECT_EQ(small.body->mesh.cells, Eigen::Vector3i(12, 12, 5));
  EXPECT_EQ((small.body->mesh.cells.array() + 1).prod(), 1014);
  EXPECT_EQ(5 * small.body->mesh.cells.prod(), 3600);  // five tets per lattice cell
  EXPECT_EQ(small.dt_s, 1.0 / 60.0);
  EXPECT_EQ(small.num_steps, 200);
  EXPECT_EQ(small.body->material.youngs_modulus_Pa, 50e3);
  EXPECT_EQ(small.body->material.poisson_ratio, 0.45);
  ASSERT_EQ(small.body->probes.size(), 1u);
  EXPECT_EQ(small.body->probes[0].name, "top_center");
  ExpectFixedFaceAndProbesOnNodes("scenes/block_small.yaml", 2, 13 * 13);
  ExpectFixedFaceAndProbesOnNodes("scenes/block_large.yaml", 2, 25 * 25);
  EXPECT_EQ(LoadScene("scenes/block_large.yaml").body->mesh.cells, Eigen::Vector3i(24, 24, 10));
}

TEST(LoadSceneTest, CantileverIsClampedAtXZero) {
  ExpectFixedFaceAndProbesOnNodes("scenes/cantilever.yaml", 0, 5 * 5);
}

}  // namespace
}  // namespace hapsim::config
