#pragma once
// Exact signed distance from a point to the rigid tool's surface, in the tool frame T (origin at
// the centre of mass, z the axis of a capsule or cylinder; core/tool_shape.h), and the tool's
// sharp features (corners, rim, mesh vertices) for tool-feature-versus-body-face contacts.
//
// Sign: negative inside the tool. For a point outside, the normal is (p − closest)/|p − closest|;
// inside, the outward normal of the nearest face (which is the gradient of the signed distance
// wherever it is differentiable, i.e. away from the medial axis).

#include <Eigen/Core>
#include <vector>

#include "core/closest_points.h"
#include "core/eigen_types.h"
#include "core/tool_shape.h"

namespace hapsim::contact {

struct ToolDistance {
  double distance_m = 0.0;                                // signed, negative inside, m
  Eigen::Vector3d closest_T_m = Eigen::Vector3d::Zero();  // closest point on the surface, T, m
  Eigen::Vector3d normal_T = Eigen::Vector3d::UnitZ();    // outward unit normal there, T
};

// Primitives, centred on the origin of T. Where the normal is not unique (the centre of a sphere,
// the axis of a capsule or cylinder), a fixed valid choice is returned.
ToolDistance CalcSphereDistance(double radius_m, const Eigen::Vector3d& p_T_m);
// Capsule: the points within radius_m of the segment z ∈ [−length_m/2, length_m/2] on the z axis.
ToolDistance CalcCapsuleDistance(double radius_m, double length_m, const Eigen::Vector3d& p_T_m);
// Cylinder with flat caps: ρ ≤ radius_m, |z| ≤ length_m/2. Side, caps and the rim edge. With
// edge_radius_m = e > 0 the rim is rounded: the shape is the inner cylinder (radius − e,
// length − 2e) grown by e, whose signed distance is the inner one minus e, exactly, with the
// same normal (the inner cylinder is convex).
ToolDistance CalcCylinderDistance(double radius_m, double length_m, const Eigen::Vector3d& p_T_m,
                                  double edge_radius_m = 0.0);
// Box |p_i| ≤ half_extents_m(i).
ToolDistance CalcBoxDistance(const Eigen::Vector3d& half_extents_m, const Eigen::Vector3d& p_T_m);

// Closed, outward-oriented triangle mesh. The closest point is found by brute force over the
// triangles (a per-triangle bounding sphere skips most exact tests); the sign is that of
// (p − closest)·N, N the angle-weighted pseudonormal of the closest feature (face, edge or vertex;
// Bærentzen & Aanæs, "Signed distance computation using the angle weighted pseudonormal", IEEE
// TVCG 2005), which is exact for a closed, consistently oriented, manifold mesh.
class MeshDistanceField {
 public:
  // Throws std::invalid_argument if the mesh is empty, has an index out of range or a
  // degenerate (zero-area) triangle, or an edge not shared by exactly two triangles.
  explicit MeshDistanceField(const TriangleMesh& mesh);

  ToolDistance Calc(const Eigen::Vector3d& p_T_m) const;

 private:
  TriangleMesh mesh_;
  Matrix3Xd face_normals_;                                       // (3 x F) unit outward
  Matrix3Xd vertex_pseudonormals_;                               // (3 x V) angle-weighted, unit
  Eigen::Matrix<double, 9, Eigen::Dynamic> edge_pseudonormals_;  // (9 x F) edge k = (k, k+1)
  Matrix3Xd sphere_centres_m_;                                   // (3 x F) bounding spheres
  Eigen::VectorXd sphere_radii_m_;                               // (F)
};

// Signed distance to any ToolShape (dispatch on kind; the mesh field is built once).
class ToolDistanceField {
 public:
  // Throws std::invalid_argument for a negative or all-zero primitive dimension or a bad mesh.
  explicit ToolDistanceField(const ToolShape& shape);

  ToolDistance Calc(const Eigen::Vector3d& p_T_m) const;
  const ToolShape& shape() const { return shape_; }
  // Radius of the smallest origin-centred sphere holding the tool, m.
  double bounding_radius_m() const { return bounding_radius_m_; }

 private:
  ToolShape shape_;
  std::vector<MeshDistanceField> mesh_field_;  // one entry for kMesh, else empty
  double bounding_radius_m_ = 0.0;
};

// Sharp features of the tool, in T: points that can touch a body face before any body node
// touches the tool (box corners, cylinder rim, mesh vertices), and the edges between them.
// Sphere and capsule have none (smooth: node-versus-tool contacts cover them).
struct ToolFeatures {
  Matrix3Xd vertices_T_m;                       // (3 x V) feature points on the tool surface, m
  Matrix3Xd vertex_normals_T;                   // (3 x V) unit axis of each point's normal cone
  Eigen::Matrix<int, 2, Eigen::Dynamic> edges;  // (2 x E) vertex index pairs
};

// Box: 8 corners, 12 edges. Cylinder: each rim sampled as a regular polygon of
// `cylinder_rim_segments` points (on the true rim; on a rounded rim, its points at 45° where the
// normal is (radial ± z)/√2), 2 × segments edges. Mesh: its vertices
// (normal cone axis = vertex pseudonormal) and unique edges.
// Throws std::invalid_argument if cylinder_rim_segments < 3.
ToolFeatures MakeToolFeatures(const ToolShape& shape, int cylinder_rim_segments = 32);

}  // namespace hapsim::contact
