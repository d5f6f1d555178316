// A body from `mesh: {surface: ..., cell_size_m: ...}`: meshed once, then read from the cache bit
// for bit; a broken cache entry meshed again; another cell size or an edited surface a new entry;
// the scene's own errors at the line and key.
#include "config/surface_mesh_cache.h"

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <string>

#include "config/body_builder.h"
#include "config/scene.h"
#include "core/error.h"
#include "core/shape_mesh.h"
#include "fem/mesh_io.h"
#include "tests/config/scene_test_support.h"

namespace hapsim::config {
namespace {
namespace fs = std::filesystem;
using test::ExpectBodyMeshError;
using test::ObjText;
using test::TempFolder;

// A fresh cache folder and a sphere surface file (r = 30 mm) in a temporary folder.
class SurfaceMeshCacheTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(Cache());
    ::setenv("HAPSIM_MESH_CACHE", Cache().c_str(), 1);
    WriteSphere(0.03);
  }
  void TearDown() override { ::unsetenv("HAPSIM_MESH_CACHE"); }
  void WriteSphere(double radius_m) const {
    ToolShape sphere;
    sphere.kind = ToolShape::Kind::kSphere;
    sphere.radius_m = radius_m;
    const TriangleMesh surface = MakeShapeMesh(sphere, 32);
    folder_.Write("organ.obj", ObjText(surface.vertices_m, surface.triangles));
  }
  std::string Surface() const { return (fs::path(folder_.path()) / "organ.obj").string(); }
  std::string Cache() const { return (fs::path(folder_.path()) / "cache").string(); }
  const TempFolder folder_{std::string("surface_cache_") +
                           ::testing::UnitTest::GetInstance()->current_test_info()->name()};
};

TEST_F(SurfaceMeshCacheTest, MeshesOnceThenReadsTheSameMeshBack) {
  const fem::SurfaceMeshOptions options{0.01, {}, 0.0, 0.0};
  const SurfaceMeshResult first = MeshSurfaceFile(Surface(), options);
  EXPECT_FALSE(first.from_cache);
  ASSERT_TRUE(fs::is_regular_file(first.cache_file));
  const SurfaceMeshResult second = MeshSurfaceFile(Surface(), options);
  EXPECT_TRUE(second.from_cache);
  EXPECT_EQ(second.cache_file, first.cache_file);
  EXPECT_EQ(second.mesh.rest_positions_m, first.mesh.rest_positions_m);  // bit for bit
  EXPECT_EQ(second.mesh.tets, first.mesh.tets);
  // Another cell size is another entry; so is an edited surface.
  const SurfaceMeshResult coarser = MeshSurfaceFile(Surface(), {0.015, {}, 0.0, 0.0});
  EXPECT_FALSE(coarser.from_cache);
  EXPECT_NE(coarser.cache_file, first.cache_file);
  // A transform is part of the key too, and applies before meshing (cell size in metres after it):
  // twice the size, 8 times the volume, to the meshes' few % of faceting.
  MeshTransform doubled;
  doubled.scale = 2.0;
  const SurfaceMeshResult big = MeshSurfaceFile(Surface(), {0.02, {}, 0.0, 0.0}, doubled);
  EXPECT_FALSE(big.from_cache);
  EXPECT_NEAR(
      fem::CalcTetMeshQuality(big.mesh).volume_m3 / fem::CalcTetMeshQuality(first.mesh).volume_m3,
      8.0, 0.4);
  WriteSphere(0.031);
  const SurfaceMeshResult edited = MeshSurfaceFile(Surface(), options);
  EXPECT_FALSE(edited.from_cache);
  EXPECT_NE(edited.cache_file, first.cache_file);
}

TEST_F(SurfaceMeshCacheTest, MeshesABrokenEntryAgain) {
  const fem::SurfaceMeshOptions options{0.01, {}, 0.0, 0.0};
  const SurfaceMeshResult first = MeshSurfaceFile(Surface(), options);
  std::ofstream(first.cache_file) << "$MeshFormat\n4.1 0 8\n";  // cut short
  const SurfaceMeshResult again = MeshSurfaceFile(Surface(), options);
  EXPECT_FALSE(again.from_cache);
  EXPECT_EQ(again.mesh.tets, first.mesh.tets);
  EXPECT_EQ(fem::ReadGmshMesh(first.cache_file).tets, first.mesh.tets);  // rewritten whole
}

TEST_F(SurfaceMeshCacheTest, SceneBodyFromASurface) {
  const std::string yaml = R"(name: surface_body
time: {dt_s: 0.01, num_steps: 1}
body:
  mesh: {surface: organ.obj, cell_size_m: 0.01}
  material: {youngs_modulus_Pa: 5000, poisson_ratio: 0.45, density_kg_m3: 1000}
)";
  const Scene scene = ParseScene(yaml, "surface_body.yaml", folder_.path());
  ASSERT_EQ(scene.body->mesh.kind, MeshSource::Kind::kSurface);
  const Body body = MakeBody(*scene.body, scene.gravity_m_s2);
  // Its mass is ρ times the tets' volume, within 5 % of the sphere's at this coarse size.
  const double sphere_m3 = 4.0 / 3.0 * M_PI * 0.03 * 0.03 * 0.03;
  EXPECT_NEAR(body.model.node_mass_kg.sum() / (1000.0 * sphere_m3), 1.0, 0.05);
}

TEST_F(SurfaceMeshCacheTest, SceneErrorsNameLineAndKey) {
  ExpectBodyMeshError("{surface: organ.obj}", "body.mesh.cell_size_m", "missing", folder_.path());
  ExpectBodyMeshError("{surface: organ.obj, cell_size_m: 0}", "body.mesh.cell_size_m", "> 0",
                      folder_.path());
  ExpectBodyMeshError("{surface: none.obj, cell_size_m: 0.01}", "body.mesh.surface", "no such file",
                      folder_.path());
  ExpectBodyMeshError("{surface: organ.msh, cell_size_m: 0.01}", "body.mesh.surface",
                      ".obj or an .stl", folder_.path());
  ExpectBodyMeshError("{box: {min_m: [0,0,0], max_m: [1,1,1], cells: [1,1,1]}, cell_size_m: 0.01}",
                      "body.mesh.cell_size_m", "surface mesh only", folder_.path());
  ExpectBodyMeshError(
      "{surface: organ.obj, cell_size_m: 0.01, refine: {near_m: [0,0,0], cell_size_m: 0.02, "
      "radius_m: 0.01}}",
      "body.mesh.refine.cell_size_m", "must not exceed", folder_.path());
}

}  // namespace
}  // namespace hapsim::config
