#pragma once
// Shape and mass properties of the rigid tool (DESIGN.md §3, §4).
//
// Tool frame T: origin at the centre of mass, axes along the principal axes of the primitive
// (z = axis of a capsule or cylinder). A mesh given in any frame is re-centred on its centroid
// by MakeToolModel (rigid_tool.h); its inertia is generally not diagonal, so the full 3×3 body
// inertia is kept everywhere.

#include <Eigen/Core>
#include <string>

#include "core/eigen_types.h"

namespace hapsim {

// A closed triangle surface. vertices_m (3 × V) in metres; triangles (3 × F) vertex indices,
// counter-clockwise seen from outside (outward normal = (b − a) × (c − a)).
struct TriangleMesh {
  Matrix3Xd vertices_m;
  Matrix3Xi triangles;
};

struct ToolShape {
  enum class Kind { kSphere, kCapsule, kCylinder, kBox, kMesh };
  Kind kind = Kind::kSphere;
  double radius_m = 0.0;  // sphere, capsule, cylinder
  // Capsule: length of the segment between the cap centres; cylinder: full height. Both along
  // the tool z axis, centred on the origin of T.
  double length_m = 0.0;
  // Cylinder: radius of its rounded rim, 0 (sharp) to min(radius_m, length_m/2). The rounded
  // cylinder is the Minkowski sum of a cylinder (radius − e, length − 2e) and a ball of radius e.
  // A sharp rim catches body nodes on its side wall as the tool slides (the closest-feature
  // normal there is horizontal), which pins them against it; real instruments are not sharp.
  double edge_radius_m = 0.0;
  Eigen::Vector3d half_extents_m = Eigen::Vector3d::Zero();  // box, centred, axes of T
  TriangleMesh mesh;  // kMesh: closed, outward-oriented, in the tool frame T
};

// Mass, centre of mass (in the frame the shape is given in) and inertia about the centre of
// mass (same axes), for a uniform density.
struct MassProperties {
  double mass_kg = 0.0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_com_kg_m2 = Eigen::Matrix3d::Zero();
};

// Primitives: exact closed forms (com = 0, diagonal inertia). Mesh: volume integrals turned
// into surface sums by the divergence theorem (Eberly, "Polyhedral Mass Properties (Revisited)",
// 2002; Mirtich 1996), exact for the polyhedron.
// Throws std::invalid_argument if density ≤ 0, a primitive dimension is negative or all zero, or
// a mesh is empty, has an index out of range, or has volume ≤ 0 (open or inward mesh).
MassProperties CalcMassProperties(const ToolShape& shape, double density_kg_m3);

// Closedness and orientation of a triangle mesh: every directed edge (a, b) appears once and its
// reverse (b, a) once (each edge shared by two triangles with opposite orientation). Returns −1
// if so; otherwise the index of a triangle with an offending edge (or a degenerate or
// out-of-range index) and a description in *message.
int FindOpenOrMisorientedTriangle(const TriangleMesh& mesh, std::string* message);

// Signed enclosed volume (1/6) Σ a · (b × c), m³: positive for a closed outward mesh.
double CalcSignedVolume_m3(const TriangleMesh& mesh);

}  // namespace hapsim
