#pragma once
// What a triangle mesh returned by hapsim::ReadTriangleMesh must satisfy (core/triangle_mesh_io.h:
// closed, consistently and outward oriented, enclosing a volume), checked by the OBJ and STL fuzz
// targets, and what the scene does with it next: the tool's mass properties.

#include <cmath>
#include <string>

#include "core/tool_shape.h"
#include "tests/fuzz/fuzz_support.h"

namespace hapsim::fuzz {

inline void CheckReadTriangleMesh(const TriangleMesh& mesh) {
  std::string defect;
  CheckOrDie(FindOpenOrMisorientedTriangle(mesh, &defect) < 0,
             "ReadTriangleMesh returned an open or misoriented mesh: " + defect);
  const double volume_m3 = CalcSignedVolume_m3(mesh);
  CheckOrDie(std::isfinite(volume_m3) && volume_m3 > 0.0,
             "ReadTriangleMesh returned a mesh of volume " + std::to_string(volume_m3) + " m^3");
  ToolShape shape;
  shape.kind = ToolShape::Kind::kMesh;
  shape.mesh = mesh;
  // config::ParseScene's next step with a tool mesh; a steel-like density.
  const MassProperties mass = CalcMassProperties(shape, 7800.0);
  CheckOrDie(std::isfinite(mass.mass_kg) && mass.mass_kg > 0.0 && mass.com_m.allFinite() &&
                 mass.inertia_com_kg_m2.allFinite(),
             "a mesh ReadTriangleMesh accepted has mass " + std::to_string(mass.mass_kg) +
                 " kg or non-finite centre of mass or inertia");
}

}  // namespace hapsim::fuzz
