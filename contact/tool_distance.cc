#include "contact/tool_distance.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>

namespace hapsim::contact {
namespace {

using Eigen::Vector3d;

// Unit vector along (x, y, 0), or +x on the z axis.
Vector3d RadialDirection(const Vector3d& p) {
  const double rho = std::hypot(p.x(), p.y());
  return rho > 0.0 ? Vector3d(p.x() / rho, p.y() / rho, 0.0) : Vector3d::UnitX();
}

// Distance to the surface of the ball of `radius_m` around `centre` (sphere, capsule).
ToolDistance CalcBallDistance(double radius_m, const Vector3d& centre, const Vector3d& p) {
  const Vector3d offset = p - centre;
  const double norm = offset.norm();
  ToolDistance result;
  result.normal_T = norm > 0.0 ? Vector3d(offset / norm) : RadialDirection(offset);
  result.distance_m = norm - radius_m;
  result.closest_T_m = centre + radius_m * result.normal_T;
  return result;
}

struct MeshNormals {
  Matrix3Xd face;                                      // (3 x F)
  Matrix3Xd vertex;                                    // (3 x V) angle-weighted
  Eigen::Matrix<double, 9, Eigen::Dynamic> edge;       // (9 x F) edge k of each face
  Eigen::Matrix<int, 2, Eigen::Dynamic> unique_edges;  // (2 x E)
};

// Face, angle-weighted vertex and edge pseudonormals; checks the mesh is closed and manifold.
MeshNormals CalcMeshNormals(const TriangleMesh& mesh) {
  const Eigen::Index num_vertices = mesh.vertices_m.cols(), num_faces = mesh.triangles.cols();
  if (num_vertices == 0 || num_faces == 0) throw std::invalid_argument("tool mesh is empty");
  MeshNormals normals;
  normals.face.resize(3, num_faces);
  normals.vertex.setZero(3, num_vertices);
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  for (Eigen::Index f = 0; f < num_faces; ++f) {
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangles(k, f);
      if (v < 0 || v >= num_vertices)
        throw std::invalid_argument("tool mesh: triangle " + std::to_string(f) +
                                    " has a vertex index out of range");
    }
    const Vector3d a = mesh.vertices_m.col(mesh.triangles(0, f));
    const Vector3d b = mesh.vertices_m.col(mesh.triangles(1, f));
    const Vector3d c = mesh.vertices_m.col(mesh.triangles(2, f));
    const Vector3d cross = (b - a).cross(c - a);
    if (!(cross.norm() > 0.0))
      throw std::invalid_argument("tool mesh: triangle " + std::to_string(f) + " is degenerate");
    normals.face.col(f) = cross.normalized();
    const Vector3d corners[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
      const Vector3d e1 = (corners[(k + 1) % 3] - corners[k]).normalized();
      const Vector3d e2 = (corners[(k + 2) % 3] - corners[k]).normalized();
      const double angle = std::acos(std::clamp(e1.dot(e2), -1.0, 1.0));
      normals.vertex.col(mesh.triangles(k, f)) += angle * normals.face.col(f);
      const int i = mesh.triangles(k, f), j = mesh.triangles((k + 1) % 3, f);
      edge_faces[{std::min(i, j), std::max(i, j)}].push_back(static_cast<int>(f));
    }
  }
  normals.vertex.colwise().normalize();
  normals.edge.resize(9, num_faces);
  normals.unique_edges.resize(2, static_cast<Eigen::Index>(edge_faces.size()));
  Eigen::Index e = 0;
  for (const auto& [edge, faces] : edge_faces) {
    if (faces.size() != 2)
      throw std::invalid_argument("tool mesh is not closed and manifold: edge (" +
                                  std::to_string(edge.first) + ", " + std::to_string(edge.second) +
                                  ") is used by " + std::to_string(faces.size()) + " triangles");
    normals.unique_edges.col(e++) << edge.first, edge.second;
    const Vector3d normal = (normals.face.col(faces[0]) + normals.face.col(faces[1])).normalized();
    for (int f : faces)
      for (int k = 0; k < 3; ++k) {
        const int i = mesh.triangles(k, f), j = mesh.triangles((k + 1) % 3, f);
        if (std::min(i, j) == edge.first && std::max(i, j) == edge.second)
          normals.edge.block<3, 1>(3 * k, f) = normal;
      }
  }
  return normals;
}

void CheckPrimitive(const ToolShape& shape) {
  const auto fail = [](const std::string& message) {
    throw std::invalid_argument("tool shape: " + message);
  };
  switch (shape.kind) {
    case ToolShape::Kind::kSphere:
      if (!(shape.radius_m > 0.0)) fail("sphere radius must be > 0");
      break;
    case ToolShape::Kind::kCapsule:
      if (!(shape.radius_m > 0.0) || !(shape.length_m >= 0.0))
        fail("capsule needs radius > 0 and length >= 0");
      break;
    case ToolShape::Kind::kCylinder:
      if (!(shape.radius_m > 0.0) || !(shape.length_m > 0.0))
        fail("cylinder needs radius > 0 and length > 0");
      if (!(shape.edge_radius_m >= 0.0) || shape.edge_radius_m > shape.radius_m ||
          shape.edge_radius_m > 0.5 * shape.length_m)
        fail("cylinder edge radius must be in [0, min(radius, length/2)]");
      break;
    case ToolShape::Kind::kBox:
      if (!(shape.half_extents_m.minCoeff() >= 0.0) || !(shape.half_extents_m.maxCoeff() > 0.0))
        fail("box half extents must be >= 0 and not all zero");
      break;
    case ToolShape::Kind::kMesh:
      break;
  }
}

}  // namespace

ToolDistance CalcSphereDistance(double radius_m, const Vector3d& p_T_m) {
  return CalcBallDistance(radius_m, Vector3d::Zero(), p_T_m);
}

ToolDistance CalcCapsuleDistance(double radius_m, double length_m, const Vector3d& p_T_m) {
  const double half_m = 0.5 * length_m;
  return CalcBallDistance(radius_m, Vector3d(0.0, 0.0, std::clamp(p_T_m.z(), -half_m, half_m)),
                          p_T_m);
}

ToolDistance CalcCylinderDistance(double radius_m, double length_m, const Vector3d& p_T_m,
                                  double edge_radius_m) {
  if (edge_radius_m > 0.0) {
    ToolDistance inner = CalcCylinderDistance(radius_m - edge_radius_m,
                                              length_m - 2.0 * edge_radius_m, p_T_m);
    inner.distance_m -= edge_radius_m;
    inner.closest_T_m += edge_radius_m * inner.normal_T;
    return inner;
  }
  const Vector3d radial = RadialDirection(p_T_m);
  const double cap_sign = p_T_m.z() >= 0.0 ? 1.0 : -1.0;
  const double side_excess_m = std::hypot(p_T_m.x(), p_T_m.y()) - radius_m;
  const double cap_excess_m = std::abs(p_T_m.z()) - 0.5 * length_m;
  ToolDistance result;
  if (side_excess_m > 0.0 && cap_excess_m > 0.0) {  // nearest the rim edge
    result.closest_T_m = radius_m * radial + Vector3d(0.0, 0.0, cap_sign * 0.5 * length_m);
    result.distance_m = std::hypot(side_excess_m, cap_excess_m);
    result.normal_T = (p_T_m - result.closest_T_m) / result.distance_m;
  } else if (side_excess_m > cap_excess_m) {  // side (outside, or inside nearer the side)
    result.closest_T_m = radius_m * radial + Vector3d(0.0, 0.0, p_T_m.z());
    result.distance_m = side_excess_m;
    result.normal_T = radial;
  } else {  // cap
    result.closest_T_m = Vector3d(p_T_m.x(), p_T_m.y(), cap_sign * 0.5 * length_m);
    result.distance_m = cap_excess_m;
    result.normal_T = Vector3d(0.0, 0.0, cap_sign);
  }
  return result;
}

ToolDistance CalcBoxDistance(const Vector3d& half_extents_m, const Vector3d& p_T_m) {
  const Vector3d excess_m = p_T_m.cwiseAbs() - half_extents_m;
  ToolDistance result;
  if ((excess_m.array() > 0.0).any()) {  // outside: the clamped point is the closest
    result.closest_T_m = p_T_m.cwiseMax(-half_extents_m).cwiseMin(half_extents_m);
    const Vector3d offset = p_T_m - result.closest_T_m;
    result.distance_m = offset.norm();
    result.normal_T = offset / result.distance_m;
    return result;
  }
  int axis = 0;  // inside: the face of least depth
  result.distance_m = excess_m.maxCoeff(&axis);
  const double sign = p_T_m[axis] >= 0.0 ? 1.0 : -1.0;
  result.closest_T_m = p_T_m;
  result.closest_T_m[axis] = sign * half_extents_m[axis];
  result.normal_T = sign * Vector3d::Unit(axis);
  return result;
}

MeshDistanceField::MeshDistanceField(const TriangleMesh& mesh) : mesh_(mesh) {
  MeshNormals normals = CalcMeshNormals(mesh_);
  face_normals_ = std::move(normals.face);
  vertex_pseudonormals_ = std::move(normals.vertex);
  edge_pseudonormals_ = std::move(normals.edge);
  const Eigen::Index num_faces = mesh_.triangles.cols();
  sphere_centres_m_.resize(3, num_faces);
  sphere_radii_m_.resize(num_faces);
  for (Eigen::Index f = 0; f < num_faces; ++f) {
    Vector3d centre = Vector3d::Zero();
    for (int k = 0; k < 3; ++k) centre += mesh_.vertices_m.col(mesh_.triangles(k, f)) / 3.0;
    double radius = 0.0;
    for (int k = 0; k < 3; ++k)
      radius = std::max(radius, (mesh_.vertices_m.col(mesh_.triangles(k, f)) - centre).norm());
    sphere_centres_m_.col(f) = centre;
    sphere_radii_m_[f] = radius;
  }
}

ToolDistance MeshDistanceField::Calc(const Vector3d& p_T_m) const {
  double best_m = std::numeric_limits<double>::infinity();
  TrianglePoint best;
  Eigen::Index best_face = 0;
  for (Eigen::Index f = 0; f < mesh_.triangles.cols(); ++f) {
    if ((p_T_m - sphere_centres_m_.col(f)).norm() - sphere_radii_m_[f] >= best_m) continue;
    const TrianglePoint candidate = CalcClosestPointOnTriangle(
        p_T_m, mesh_.vertices_m.col(mesh_.triangles(0, f)),
        mesh_.vertices_m.col(mesh_.triangles(1, f)), mesh_.vertices_m.col(mesh_.triangles(2, f)));
    const double distance_m = (p_T_m - candidate.point).norm();
    if (distance_m < best_m) {
      best_m = distance_m;
      best = candidate;
      best_face = f;
    }
  }
  Vector3d pseudonormal;
  if (best.feature < 3)
    pseudonormal = vertex_pseudonormals_.col(mesh_.triangles(best.feature, best_face));
  else if (best.feature < 6)
    pseudonormal = edge_pseudonormals_.block<3, 1>(3 * (best.feature - 3), best_face);
  else
    pseudonormal = face_normals_.col(best_face);
  const Vector3d offset = p_T_m - best.point;
  const double sign = offset.dot(pseudonormal) >= 0.0 ? 1.0 : -1.0;
  ToolDistance result;
  result.closest_T_m = best.point;
  result.distance_m = sign * best_m;
  if (best.feature == 6)
    result.normal_T = pseudonormal;  // the face normal, inside or out
  else
    result.normal_T = best_m > 0.0 ? Vector3d(sign * offset / best_m) : pseudonormal;
  return result;
}

ToolDistanceField::ToolDistanceField(const ToolShape& shape) : shape_(shape) {
  CheckPrimitive(shape_);
  switch (shape_.kind) {
    case ToolShape::Kind::kSphere:
      bounding_radius_m_ = shape_.radius_m;
      break;
    case ToolShape::Kind::kCapsule:
      bounding_radius_m_ = shape_.radius_m + 0.5 * shape_.length_m;
      break;
    case ToolShape::Kind::kCylinder:
      bounding_radius_m_ = std::hypot(shape_.radius_m, 0.5 * shape_.length_m);
      break;
    case ToolShape::Kind::kBox:
      bounding_radius_m_ = shape_.half_extents_m.norm();
      break;
    case ToolShape::Kind::kMesh:
      mesh_field_.emplace_back(shape_.mesh);
      bounding_radius_m_ = shape_.mesh.vertices_m.colwise().norm().maxCoeff();
      break;
  }
}

ToolDistance ToolDistanceField::Calc(const Vector3d& p_T_m) const {
  switch (shape_.kind) {
    case ToolShape::Kind::kSphere:
      return CalcSphereDistance(shape_.radius_m, p_T_m);
    case ToolShape::Kind::kCapsule:
      return CalcCapsuleDistance(shape_.radius_m, shape_.length_m, p_T_m);
    case ToolShape::Kind::kCylinder:
      return CalcCylinderDistance(shape_.radius_m, shape_.length_m, p_T_m, shape_.edge_radius_m);
    case ToolShape::Kind::kBox:
      return CalcBoxDistance(shape_.half_extents_m, p_T_m);
    case ToolShape::Kind::kMesh:
      break;
  }
  return mesh_field_.front().Calc(p_T_m);
}

ToolFeatures MakeToolFeatures(const ToolShape& shape, int cylinder_rim_segments) {
  if (cylinder_rim_segments < 3) throw std::invalid_argument("cylinder_rim_segments must be >= 3");
  ToolFeatures features;
  if (shape.kind == ToolShape::Kind::kBox) {  // corner c has signs (bit 0, bit 1, bit 2)
    features.vertices_T_m.resize(3, 8);
    features.vertex_normals_T.resize(3, 8);
    for (int c = 0; c < 8; ++c) {
      const Vector3d signs((c & 1) ? 1.0 : -1.0, (c & 2) ? 1.0 : -1.0, (c & 4) ? 1.0 : -1.0);
      features.vertices_T_m.col(c) = signs.cwiseProduct(shape.half_extents_m);
      features.vertex_normals_T.col(c) = signs / std::sqrt(3.0);
    }
    features.edges.resize(2, 12);
    int e = 0;
    for (int c = 0; c < 8; ++c)
      for (int bit = 1; bit < 8; bit <<= 1)
        if (!(c & bit)) features.edges.col(e++) << c, c | bit;
  } else if (shape.kind == ToolShape::Kind::kCylinder) {
    const int n = cylinder_rim_segments;
    features.vertices_T_m.resize(3, 2 * n);
    features.vertex_normals_T.resize(3, 2 * n);
    features.edges.resize(2, 2 * n);
    for (int rim = 0; rim < 2; ++rim)
      for (int k = 0; k < n; ++k) {
        const double angle = 2.0 * M_PI * k / n, z_sign = rim == 0 ? -1.0 : 1.0;
        const double e = shape.edge_radius_m;
        const Vector3d radial(std::cos(angle), std::sin(angle), 0.0);
        const Vector3d normal = (radial + Vector3d(0.0, 0.0, z_sign)) / std::sqrt(2.0);
        features.vertices_T_m.col(rim * n + k) =
            (shape.radius_m - e) * radial +
            Vector3d(0.0, 0.0, z_sign * (0.5 * shape.length_m - e)) + e * normal;
        features.vertex_normals_T.col(rim * n + k) = normal;
        features.edges.col(rim * n + k) << rim * n + k, rim * n + (k + 1) % n;
      }
  } else if (shape.kind == ToolShape::Kind::kMesh) {
    MeshNormals normals = CalcMeshNormals(shape.mesh);
    features.vertices_T_m = shape.mesh.vertices_m;
    features.vertex_normals_T = std::move(normals.vertex);
    features.edges = std::move(normals.unique_edges);
  }
  return features;
}

}  // namespace hapsim::contact
