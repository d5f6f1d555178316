#pragma once
// Tetrahedral meshes from a regular lattice of cubes, each cut into five tets.
//
// The five-tet cut alternates with the parity of (i + j + k) so that neighbouring cells share
// face diagonals and the mesh is conforming. An nx × ny × nz box has (nx+1)(ny+1)(nz+1) nodes and
// 5·nx·ny·nz tets (12 × 12 × 5 cells: 1,014 nodes, 3,600 tets, as in DESIGN.md §7).

#include <Eigen/Core>
#include <functional>

#include "fem/tet_mesh.h"

namespace hapsim::fem {

// Box [min_m, max_m] cut into cells(0) × cells(1) × cells(2) lattice cells.
// Preconditions (throws std::invalid_argument): max_m > min_m on each axis, cells ≥ 1.
TetMesh MakeBoxTetMesh(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m,
                       const Eigen::Vector3i& cells);

// Signed distance-like function: negative inside the body, positive outside, zero on its
// surface, Lipschitz near the surface (a true signed distance is best).
using ImplicitFunction = std::function<double(const Eigen::Vector3d& p_m)>;

// Cut-lattice mesher: a lattice of cubic cells of edge `cell_size_m` over [min_m, max_m], keeping
// the tets whose centroid is inside (φ < 0), then moving boundary nodes onto the surface φ = 0
// by a Newton step along ∇φ (finite differences) where that keeps every tet of good quality.
// Throws std::invalid_argument if no tet is inside.
TetMesh MakeImplicitTetMesh(const ImplicitFunction& phi, const Eigen::Vector3d& min_m,
                            const Eigen::Vector3d& max_m, double cell_size_m);

// Approximate signed distance to the ellipsoid with centre c and radii r: (|(p−c)/r| − 1)·min(r).
ImplicitFunction MakeEllipsoidFunction(const Eigen::Vector3d& center_m,
                                       const Eigen::Vector3d& radii_m);

}  // namespace hapsim::fem
