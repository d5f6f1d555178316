#pragma once
// Tetrahedra from a closed triangle surface (issue 26): an organ surface from a segmentation
// (OBJ/STL, read by ReadTriangleMesh) filled with tets of a chosen size for the FEM, by the Gmsh
// API (Debian's libgmsh-dev). The surface is first remeshed at the same size (Gmsh reparametrises
// it patch by patch, so the new surface nodes lie on the given triangles), then the volume is
// filled (Delaunay) and optimised. The mechanics then run on a mesh as coarse as a frame affords,
// whatever the resolution of the surface a user brings.
//
// Why Gmsh rather than CGAL's Mesh_3 (both measured on the same surfaces by
// tests/bench/mesher_comparison.cc; docs/SCENES.md has the table): see the comment at
// MeshClosedSurface.
//
// Grading: `refine` gives points near which the cells are finer (a contact region): the size is
// refine_cell_size_m within refine_radius_m of the nearest point, growing linearly to cell_size_m
// at twice that distance (Gmsh's Distance and Threshold fields).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/tool_shape.h"
#include "fem/tet_mesh.h"

namespace hapsim::fem {

struct SurfaceMeshOptions {
  double cell_size_m = 0.0;                    // target edge length of the tets, > 0
  std::vector<Eigen::Vector3d> refine_near_m;  // optional: where the cells are finer
  double refine_cell_size_m = 0.0;             // (0, cell_size_m] when refine_near_m is given
  double refine_radius_m = 0.0;                // > 0 when refine_near_m is given
};

// Bounds on one meshing: the tets (estimated from the volume before meshing) and the time Gmsh may
// take, in its own process (a surface it cannot handle may make it hang or crash; either becomes
// an InputError here, never a hung or dead hapsim).
struct SurfaceMeshLimits {
  int max_tets = 2'000'000;
  double timeout_s = 300.0;
};

// Fills `surface` (closed and outward-oriented, as ReadTriangleMesh returns it) with tets.
// The result follows the readers' conventions (fem/mesh_io.h): compact nodes, every tet
// positively oriented, none degenerate. `label` names the surface in errors (its file).
// Throws InputError(label, 0, key, message) for options out of range (key "cell_size_m", ...), a
// cell size so small against the surface that the mesh would exceed limits.max_tets (key
// "cell_size_m"), a surface in several pieces, and one the mesher cannot fill, crashes on or takes
// longer than limits.timeout_s over (key "surface", with Gmsh's own message where it gave one).
TetMesh MeshClosedSurface(const TriangleMesh& surface, const SurfaceMeshOptions& options,
                          const std::string& label, const SurfaceMeshLimits& limits = {});

// Names the mesher and its library version (for caches keyed by what made a mesh).
std::string SurfaceMesherVersion();

}  // namespace hapsim::fem
