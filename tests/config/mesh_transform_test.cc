// A mesh file's `units` and `transform` (core/mesh_transform.h): a mesh written in millimetres,
// turned and shifted, loads as the same mesh written in metres in place; for a deformable body's
// tet file, a rigid object's and a tool's surface alike. And the refusals, at the line and key.
#include "core/mesh_transform.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <filesystem>
#include <string>

#include "config/body_builder.h"
#include "config/scene.h"
#include "core/error.h"
#include "core/shape_mesh.h"
#include "fem/lattice_mesher.h"
#include "fem/mesh_io.h"
#include "tests/config/scene_test_support.h"

namespace hapsim::config {
namespace {
namespace fs = std::filesystem;
using test::ExpectBodyMeshError;
using test::ObjText;
using test::TempFolder;

// The placement the scenes below give, and its inverse for writing the files.
// A quarter turn about x with a tilt, as a y-up file needs; the inverse is applied to write it.
const Eigen::Vector3d kRotationVector_rad(-0.5 * M_PI, 0.3, 0.0);
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
  const TempFolder folder_{std::string("mesh_transform_") +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name()};
  std::string PathOf(const std::string& name) const {
    return (fs::path(folder_.path()) / name).string();
  }
};

TEST_F(MeshTransformTest, DeformableFileInMillimetresTurnedAndShifted) {
  const fem::TetMesh in_place = fem::MakeBoxTetMesh({0.0, 0.0, 0.0}, {0.04, 0.02, 0.01}, {4, 2, 2});
  fem::TetMesh in_file = in_place;
  in_file.rest_positions_m = ToFileCoordinates(in_place.rest_positions_m);
  fem::WriteGmshMesh(in_file, PathOf("body.msh"), 4);
  const std::string yaml = std::string(R"(name: t
time: {dt_s: 0.01, num_steps: 1}
body:
  mesh: {file: body.msh, )") +
                           kTransform + R"(}
  material: {youngs_modulus_Pa: 1000, poisson_ratio: 0.3, density_kg_m3: 1000}
)";
  const Scene scene = ParseScene(yaml, "t.yaml", folder_.path());
  const Body body = MakeBody(*scene.body, scene.gravity_m_s2);
  EXPECT_EQ(body.model.mesh.tets, in_place.tets);
  EXPECT_LT((body.model.mesh.rest_positions_m - in_place.rest_positions_m).cwiseAbs().maxCoeff(),
            1e-15);
  EXPECT_NEAR(body.model.node_mass_kg.sum(), 1000.0 * 0.04 * 0.02 * 0.01, 1e-15);
}

// The same for surfaces: a rigid object's mesh stays in its own frame, so its vertices must be
// the ones in place; the tool's model moves its mesh to the centre of mass, so its edge vectors
// (which that leaves alone) must be.
TEST_F(MeshTransformTest, SurfacesInMillimetresTurnedAndShifted) {
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Eigen::Vector3d(0.01, 0.005, 0.002);
  TriangleMesh in_place = MakeShapeMesh(box);
  in_place.vertices_m.colwise() += kTranslation_m;  // off centre, as a file may be
  folder_.Write("part.obj", ObjText(ToFileCoordinates(in_place.vertices_m), in_place.triangles));
  const std::string mesh = std::string("{mesh: {file: part.obj, ") + kTransform + "}}";
  const std::string yaml = R"(name: t
time: {dt_s: 0.01, num_steps: 1}
objects:
  - name: part
    rigid:
      shape: )" + mesh + R"(
tool:
  shape: )" + mesh + R"(
  mass_kg: 0.01
coupling: {k_lin_N_m: 100, b_lin_N_s_m: 1, k_ang_N_m_rad: 1, b_ang_N_m_s_rad: 0.01}
contact: {law: unilateral}
device:
  trajectory:
    - {t_s: 0.0, position_m: [0, 0, 0.5]}
)";
  const Scene scene = ParseScene(yaml, "t.yaml", folder_.path());
  ASSERT_EQ(scene.rigid_objects.size(), 1u);
  const TriangleMesh& object = scene.rigid_objects[0].object.shape.mesh;
  ASSERT_EQ(object.vertices_m.cols(), in_place.vertices_m.cols());
  EXPECT_LT((object.vertices_m - in_place.vertices_m).cwiseAbs().maxCoeff(), 1e-15);
  ASSERT_TRUE(scene.tool.has_value());
  const TriangleMesh& tool = scene.tool->model.shape.mesh;
  ASSERT_EQ(tool.vertices_m.cols(), in_place.vertices_m.cols());
  for (Eigen::Index v = 1; v < in_place.vertices_m.cols(); ++v)
    EXPECT_LT(((tool.vertices_m.col(v) - tool.vertices_m.col(0)) -
               (in_place.vertices_m.col(v) - in_place.vertices_m.col(0)))
                  .norm(),
              1e-15);
}

TEST_F(MeshTransformTest, RefusesABadTransformAtItsLineAndKey) {
  fem::WriteGmshMesh(fem::MakeBoxTetMesh({0, 0, 0}, {1, 1, 1}, {1, 1, 1}), PathOf("body.msh"), 4);
  ExpectBodyMeshError("{file: body.msh, transform: {scale: 0}}", "body.mesh.transform.scale", "> 0",
                      folder_.path());
  ExpectBodyMeshError("{file: body.msh, transform: {scale: -2}}", "body.mesh.transform.scale",
                      "> 0", folder_.path());
  ExpectBodyMeshError("{file: body.msh, units: inch}", "body.mesh.units", "mm", folder_.path());
  ExpectBodyMeshError("{box: {min_m: [0,0,0], max_m: [1,1,1], cells: [1,1,1]}, units: mm}",
                      "body.mesh.units", "box and ellipsoid are in metres", folder_.path());
}

}  // namespace
}  // namespace hapsim::config
