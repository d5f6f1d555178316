#pragma once
// Quadratic tets with curved boundary faces (issue 27 item 3): the edge nodes of a quadratic mesh
// made from a linear one (MakeQuadraticMesh) sit at their edges' midpoints, so a body cut from a
// user's organ surface keeps the flat facets of its linear boundary. Moving each boundary edge node
// to the closest point of that surface makes the P2 faces bend with it (the geometry is
// isoparametric, fem/quadratic_tet.h): a sphere of flat facets becomes a sphere of curved patches,
// and the volume, mass and contact surface follow the organ more closely at the same mesh.
//
// A move that would fold an element, or bend it so far that det(∂x/∂ξ) falls below a fifth of its
// straight tet's anywhere the element is checked (FindQuadraticTetProblem's corners and quadrature
// points), or that is longer than a quarter of the edge (the surface is not the one the mesh was
// cut from), is not made: that node stays at its midpoint, and the report counts it. Interior edge
// nodes never move, so an element can only curve where it touches the boundary; the tets behind a
// strongly curved boundary face need cells small against the surface's radius of curvature, which
// Gmsh's sizing gives the user's surface.

#include "core/eigen_types.h"
#include "fem/tet_mesh.h"

namespace hapsim::fem {

struct CurvedBoundaryReport {
  int num_boundary_edge_nodes = 0;
  int num_moved = 0;        // moved onto the surface
  int num_kept = 0;         // left at their midpoints: the move would bend a tet too far, or
                            // is too long
  double max_move_m = 0.0;  // the largest move made
};

// Moves the boundary edge nodes of `mesh` (quadratic) to their closest points on the closed
// triangle surface (vertices, triangles), as above. Throws std::invalid_argument if the mesh is
// linear or the surface has no triangle.
CurvedBoundaryReport MoveBoundaryEdgeNodesOntoSurface(const Matrix3Xd& surface_vertices_m,
                                                      const Matrix3Xi& surface_triangles,
                                                      TetMesh* mesh);

}  // namespace hapsim::fem
