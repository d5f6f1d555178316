// Fuzz target: a surface a user brings (OBJ, as ReadTriangleMesh accepts it) filled with tets by
// fem::MeshClosedSurface (Gmsh), at a cell size of an eighth of its bounding box (at most 20,000
// tets, 10 s). Whatever the surface, the mesher must end in a mesh that passes the readers' checks
// or in an InputError; a crash inside Gmsh is a finding like any other.

#include <cstddef>
#include <cstdint>

#include "core/triangle_mesh_io.h"
#include "fem/surface_mesher.h"
#include "tests/fuzz/fuzz_support.h"
#include "tests/fuzz/tet_mesh_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hapsim;
  const std::string path = fuzz::WriteScratchFile("input.obj", data, size);
  TriangleMesh surface;
  if (!fuzz::RunReader([&] { surface = ReadTriangleMesh(path); })) return 0;
  const Eigen::Vector3d extent_m =
      surface.vertices_m.rowwise().maxCoeff() - surface.vertices_m.rowwise().minCoeff();
  fem::SurfaceMeshOptions options;
  options.cell_size_m = extent_m.norm() / 8.0;
  fem::TetMesh mesh;
  if (fuzz::RunReader([&] {
        mesh = fem::MeshClosedSurface(surface, options, path, {20'000, 10.0});
      }))
    fuzz::CheckReadTetMesh(mesh);
  return 0;
}
