// A mesh file's `units` and `transform` (core/mesh_transform.h): a mesh written in millimetres,
// turned and shifted, loads as the same mesh written in metres in place; for a deformable body's
// tet file and a rigid tool's surface alike. And the refusals, at the line and key.
#include "core/mesh_transform.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <string>

#include "config/body_builder.h"
#include "config/scene.h"
#include "core/error.h"
#include "core/shape_mesh.h"
#include "fem/lattice_mesher.h"
#include "fem/mesh_io.h"

namespace hapsim::config {
namespace {
namespace fs = std::filesystem;

// The placement the scenes below give, and its inverse for writing the files.
const Eigen::Vector3d kRotationVector_rad(-0.5 * M_PI, 0.3, 0.0);  // y up to z up, and a turn
const Eigen::Vector3d kTranslation_m(0.01, -0.02, 0.03);
constexpr double kScale = 2.5;  // times the millimetres
constexpr const char* kTransform =
    "units: mm, transform: {scale: 2.5, rotation_vector_rad: [-1.5707963267948966, 0.3, 0], "
    "translation_m: [0.01, -0.02, 0.03]}";

Matrix3Xd ToFileCoordinates(const Matrix3Xd& p_m) {
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(kRotationVector_rad.norm(), kRotationVector_rad.normalized())
          .toRotationMatrix();
  return (R.transpose() * (p_m.colwise() - kTranslation_m)) / (0.001 * kScale);
}

class MeshTransformTest : public ::testing::Test {
 protected:
  void SetUp() override {
    folder_ = fs::temp_directory_path() / ("hapsim_mesh_transform_" + std::to_string(::getpid()));
    fs::create_directories(folder_);
  }
  void TearDown() override { fs::remove_all(folder_); }
  fs::path folder_;
};

TEST_F(MeshTransformTest, DeformableFileInMillimetresTurnedAndShifted) {
  const fem::TetMesh in_place = fem::MakeBoxTetMesh({0.0, 0.0, 0.0}, {0.04, 0.02, 0.01}, {4, 2, 2});
  fem::TetMesh in_file = in_place;
  in_file.rest_positions_m = ToFileCoordinates(in_place.rest_positions_m);
  fem::WriteGmshMesh(in_file, (folder_ / "body.msh").string(), 4);
  const std::string yaml = std::string(R"(name: t
time: {dt_s: 0.01, num_steps: 1}
body:
  mesh: {file: body.msh, )") +
                           kTransform + R"(}
  material: {youngs_modulus_Pa: 1000, poisson_ratio: 0.3, density_kg_m3: 1000}
)";
  const Scene scene = ParseScene(yaml, "t.yaml", folder_.string());
  const Body body = MakeBody(*scene.body, scene.gravity_m_s2);
  EXPECT_EQ(body.model.mesh.tets, in_place.tets);
  EXPECT_LT((body.model.mesh.rest_positions_m - in_place.rest_positions_m).cwiseAbs().maxCoeff(),
            1e-15);
  EXPECT_NEAR(body.model.node_mass_kg.sum(), 1000.0 * 0.04 * 0.02 * 0.01, 1e-15);
}

TEST_F(MeshTransformTest, ToolSurfaceInMillimetresTurnedAndShifted) {
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Eigen::Vector3d(0.01, 0.005, 0.002);
  TriangleMesh in_place = MakeShapeMesh(box);
  in_place.vertices_m.colwise() += kTranslation_m;  // off centre, as a file may be
  const Matrix3Xd in_file = ToFileCoordinates(in_place.vertices_m);
  {
    std::ofstream out(folder_ / "tool.obj");
    out.precision(17);
    for (Eigen::Index v = 0; v < in_file.cols(); ++v)
      out << "v " << in_file(0, v) << ' ' << in_file(1, v) << ' ' << in_file(2, v) << '\n';
    for (Eigen::Index t = 0; t < in_place.triangles.cols(); ++t)
      out << "f " << in_place.triangles(0, t) + 1 << ' ' << in_place.triangles(1, t) + 1 << ' '
          << in_place.triangles(2, t) + 1 << '\n';
  }
  const std::string yaml = std::string(R"(name: t
time: {dt_s: 0.01, num_steps: 1}
tool:
  shape: {mesh: {file: tool.obj, )") +
                           kTransform + R"(}}
  mass_kg: 0.01
coupling: {k_lin_N_m: 100, b_lin_N_s_m: 1, k_ang_N_m_rad: 1, b_ang_N_m_s_rad: 0.01}
device:
  trajectory:
    - {t_s: 0.0, position_m: [0, 0, 0]}
)";
  const Scene scene = ParseScene(yaml, "t.yaml", folder_.string());
  ASSERT_TRUE(scene.tool.has_value());
  const ToolShape& shape = scene.tool->model.shape;
  ASSERT_EQ(shape.kind, ToolShape::Kind::kMesh);
  // The tool model may re-centre its mesh on the centre of mass: compare edge vectors, which
  // that leaves alone, and the extent.
  ASSERT_EQ(shape.mesh.vertices_m.cols(), in_place.vertices_m.cols());
  for (Eigen::Index v = 1; v < in_place.vertices_m.cols(); ++v)
    EXPECT_LT(((shape.mesh.vertices_m.col(v) - shape.mesh.vertices_m.col(0)) -
               (in_place.vertices_m.col(v) - in_place.vertices_m.col(0)))
                  .norm(),
              1e-15);
}

TEST_F(MeshTransformTest, RefusesABadTransformAtItsLineAndKey) {
  fem::WriteGmshMesh(fem::MakeBoxTetMesh({0, 0, 0}, {1, 1, 1}, {1, 1, 1}),
                     (folder_ / "body.msh").string(), 4);
  const auto expect_error = [&](const std::string& mesh, const std::string& key,
                                const std::string& words) {
    const std::string yaml = "name: t\ntime: {dt_s: 0.01, num_steps: 1}\nbody:\n  mesh: " + mesh +
                             "\n  material: {youngs_modulus_Pa: 1, poisson_ratio: 0.3, "
                             "density_kg_m3: 1}\n";
    try {
      ParseScene(yaml, "t.yaml", folder_.string());
      ADD_FAILURE() << "no error for " << mesh;
    } catch (const InputError& error) {
      EXPECT_EQ(error.line(), 4) << error.what();
      EXPECT_EQ(error.key(), key) << error.what();
      EXPECT_NE(std::string(error.what()).find(words), std::string::npos) << error.what();
    }
  };
  expect_error("{file: body.msh, transform: {scale: 0}}", "body.mesh.transform.scale", "> 0");
  expect_error("{file: body.msh, transform: {scale: -2}}", "body.mesh.transform.scale", "> 0");
  expect_error("{file: body.msh, units: inch}", "body.mesh.units", "mm");
  expect_error("{box: {min_m: [0,0,0], max_m: [1,1,1], cells: [1,1,1]}, units: mm}",
               "body.mesh.units", "box and ellipsoid are in metres");
}

}  // namespace
}  // namespace hapsim::config
