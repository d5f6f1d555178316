#pragma once
// A closed triangle surface for any ToolShape (core/tool_shape.h), for the methods that need
// triangles where the visual frame uses exact distance fields: the god-object rendering's
// constraint planes (contact/god_object.h) on a rigid object that is a box, sphere, capsule or
// cylinder.
//
// Box: its 12 triangles, exact. Round shapes: surfaces of revolution about z, `segments` facets
// around, with vertices ON the true surface (so the facets lie inside it by at most the sagitta
// r (1 − cos(π/segments)), 0.5% of r at 32): a sphere from pole to pole in segments/2 rings; a
// capsule the same with its two caps apart by length; a cylinder its flat caps and side wall, with
// a rounded rim as quarter arcs of segments/4 pieces. Mesh: itself. Closed and outward oriented
// (FindOpenOrMisorientedTriangle finds nothing), in the shape's frame.

#include "core/tool_shape.h"

namespace hapsim {

// Throws std::invalid_argument if segments < 8 or the shape has a dimension ≤ 0 where it needs
// one.
TriangleMesh MakeShapeMesh(const ToolShape& shape, int segments = 32);

}  // namespace hapsim
