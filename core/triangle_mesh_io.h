#pragma once
// Reading closed triangle meshes for the tool (ToolShape::Kind::kMesh): Wavefront OBJ and STL.

#include <string>

#include "core/tool_shape.h"

namespace hapsim {

// Reads `path`, choosing the format from the extension (.obj, .stl; case-insensitive).
//  - OBJ: `v x y z [w]` and `f i j k …` lines; a polygon is fan-triangulated (i j k, i k l, …);
//    indices are 1-based, negative ones count back from the last vertex read so far; the forms
//    i, i/t, i//n, i/t/n are accepted (texture and normal indices ignored); other lines (vn,
//    vt, o, g, s, usemtl, mtllib, #…) are ignored.
//  - STL: binary when the file size is exactly 84 + 50 n (n = the count in bytes 80–83), else
//    ASCII (`solid … facet … outer loop … vertex ×3 … endloop … endfacet … endsolid`). Facet
//    normals are ignored (orientation comes from the vertex order); vertices with exactly equal
//    coordinates are merged. Binary STL is read as little-endian IEEE floats.
// Coordinates are metres as written in the file (no unit conversion), each at most 1000 m in magnitude.
// The mesh must be closed and consistently oriented (every edge used by two triangles in
// opposite directions) with non-zero volume; a mesh whose faces all point inward is flipped.
// Throws InputError naming the file and the line (ASCII formats), or, for binary STL, line 0
// and key "triangle N" (0-based); an open or misoriented mesh is reported at the line of (or
// the key of) an offending triangle. A file that cannot be opened: line 0.
TriangleMesh ReadTriangleMesh(const std::string& path);

}  // namespace hapsim
