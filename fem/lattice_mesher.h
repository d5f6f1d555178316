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

// Nodes along one axis of [min_m, max_m] in `cells` cells whose size grows linearly with the
// distance from focus_m, h(x) = h0 (1 + (ratio − 1) |x − focus| / D), D the farther end's distance:
// the cells at the farther end are `ratio` times those at the focus. The nodes are uniform in
// ∫ dx / h, which has a closed form. ratio 1: a uniform axis. For meshes fine where the contact is
// (a Hertz or punch indentation) and coarse where the field is smooth.
// Throws std::invalid_argument unless max > min, cells ≥ 1, min ≤ focus ≤ max and ratio ≥ 1.
Eigen::VectorXd MakeGradedAxis(double min_m, double max_m, int cells, double focus_m, double ratio);

// MakeBoxTetMesh with every axis graded by MakeGradedAxis towards the point focus_m.
// circle_radius_m > 0: then the lattice is bent into an O-grid about the vertical line through the
// focus, in every layer alike. Each square ring of nodes about that line moves radially onto a
// circle, so that the ring nearest circle_radius_m lies on the circle of that radius and every
// ring inside it on a smaller circle, and the move fades out over as many rings again outside it.
// A flat punch or probe of that radius then has nodes all along its rim, and no face of the body
// passes under the rim (up to the sagitta of a ring edge's chord). The rings are squares only if
// x and y have the same nodes about the focus: throws std::invalid_argument unless the focus is a
// node in x and y, the axes are the same there (x and y cells and extents about the focus alike),
// and the fade's outer ring (2k, ring k the circle's) lies within the box; and if the bend folds
// a tet (checked after the move, whatever the rings' sizes). The bend squeezes the cells along
// the square rings' diagonals: on 16 × 16 × 8 cells graded 10:1 with a 3 mm circle the worst tet's
// quality falls from 0.067 to 0.026, in the tall cells deep under the focus.
TetMesh MakeGradedBoxTetMesh(const Eigen::Vector3d& min_m, const Eigen::Vector3d& max_m,
                             const Eigen::Vector3i& cells, const Eigen::Vector3d& focus_m,
                             double ratio, double circle_radius_m = 0.0);

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
