#pragma once
// What a tet mesh returned by a reader must satisfy (the conventions at the top of fem/mesh_io.h),
// checked by the Gmsh and TetGen fuzz targets: a mesh that breaks them reaches fem::MakeModel.

#include <cmath>
#include <string>
#include <vector>

#include "fem/tet_mesh.h"
#include "tests/fuzz/fuzz_support.h"

namespace hapsim::fuzz {

inline void CheckReadTetMesh(const fem::TetMesh& mesh) {
  CheckOrDie(mesh.num_tets() > 0, "a reader returned a mesh without tets");
  const std::optional<std::string> problem = fem::FindRestMeshProblem(mesh);
  CheckOrDie(!problem, "a reader returned a mesh with a problem: " + problem.value_or(""));
  std::vector<bool> used(static_cast<size_t>(mesh.num_nodes()), false);
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const Eigen::Vector4i tet = mesh.tets.col(t);
    for (int a = 0; a < mesh.nodes_per_tet(); ++a)
      used[static_cast<size_t>(mesh.node(a, t))] = true;
    // FindRestMeshProblem compares the quality with a threshold, which a NaN quality (volume and
    // edge lengths overflowing to inf) passes; the FEM would then divide by an inf volume.
    const double volume_m3 = fem::CalcSignedVolume(mesh.rest_positions_m, tet);
    const double quality = fem::CalcTetQuality(mesh.rest_positions_m, tet);
    CheckOrDie(std::isfinite(volume_m3) && volume_m3 > 0.0 && std::isfinite(quality),
               "a reader returned tet " + std::to_string(t) + " of volume " +
                   std::to_string(volume_m3) + " m^3 and quality " + std::to_string(quality));
  }
  for (int n = 0; n < mesh.num_nodes(); ++n)
    CheckOrDie(used[static_cast<size_t>(n)],
               "a reader returned node " + std::to_string(n) + ", which no tet uses");
}

}  // namespace hapsim::fuzz
