#pragma once
// Quarter-point quadratic tets along a line where the displacement goes as the root of the
// distance (issue 27: the flat punch's rim). Under a rigid flat punch the surface displacement
// just outside the rim is d − (2d/π)·(2ρ/a)^½ to first order in ρ, the distance from the rim
// (Johnson, Contact Mechanics, §3.7, w = (2d/π) asin(a/r)), and the pressure inside goes as
// ρ^−½: the field of a mode-I crack's tip (the rim is where a region of prescribed normal
// displacement ends on a free surface). On a mesh whose cells stay finite at the rim, polynomial
// elements leave the error set by the rim's cells; an isoparametric quadratic element puts the
// leading √ρ term into them exactly if each edge node on an edge leaving the singular node sits a
// quarter of the way along (Henshell and Shaw 1975; Barsoum 1976): along the edge x(ξ) = L ξ²
// (nodes at ξ = 0, ½, 1 map to 0, L/4, L), so a field linear in ξ is √(x/L). With two singular
// corners (a tet with an edge on the singular line) the same holds for the distance from that
// edge; a tet with three (a face on the line: a chord triangle of a coarse rim) gets √ of the
// distance from that face instead, not the line's field.
//
// A move makes det(∂x/∂ξ) vanish at the singular corner when `fraction` is exactly ¼
// (∂x/∂ξ = L (4·fraction − 1) there), which FindQuadraticTetProblem refuses as a flat element;
// just above ¼ the element is regular everywhere and still close to √ρ (scripts/bench/punch_rim.py
// chooses the fraction and measures the difference). The stiffness's integrand is then no longer
// a polynomial near that corner, so the element's quadrature is not exact there.

#include <vector>

#include "fem/tet_mesh.h"

namespace hapsim::fem {

// Moves, in the quadratic `mesh`, the node of every edge with exactly one corner flagged in
// `singular` (one flag per node) to corner + fraction · (other corner − corner). Edges with both
// or neither corner flagged keep their nodes. Returns the number of edge nodes moved (each once,
// however many tets share its edge). Throws std::invalid_argument if the mesh is linear,
// `singular` has not one flag per node, or fraction is outside [¼, ½].
int MoveEdgeNodesToQuarterPoints(const std::vector<bool>& singular, double fraction,
                                 TetMesh* mesh);

}  // namespace hapsim::fem
