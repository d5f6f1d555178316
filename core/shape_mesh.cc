#include "core/shape_mesh.h"

#include <cmath>
#include <stdexcept>
#include <vector>

namespace hapsim {
namespace {

// A surface of revolution about z through the profile points (ρ, z), from the bottom pole
// (ρ = 0) to the top pole (ρ = 0), `around` facets around. Outward for a profile that goes up
// with the interior on its left (ρ decreasing to the left).
TriangleMesh MakeRevolutionMesh(std::vector<Eigen::Vector2d> profile, int around) {
  // Arcs that meet (a sphere's two caps, a rim's arcs on a cylinder of length 2e) share a point.
  for (size_t i = 1; i < profile.size();) {
    if ((profile[i] - profile[i - 1]).norm() < 1e-12 * (1.0 + profile[i].norm()))
      profile.erase(profile.begin() + static_cast<long>(i));
    else
      ++i;
  }
  const int rings = static_cast<int>(profile.size()) - 2;  // the points between the two poles
  TriangleMesh mesh;
  mesh.vertices_m.resize(3, 2 + rings * around);
  mesh.vertices_m.col(0) = Eigen::Vector3d(0, 0, profile.front().y());
  mesh.vertices_m.col(1) = Eigen::Vector3d(0, 0, profile.back().y());
  auto vertex = [around](int ring, int k) { return 2 + ring * around + (k % around); };
  for (int ring = 0; ring < rings; ++ring) {
    const Eigen::Vector2d& p = profile[ring + 1];
    for (int k = 0; k < around; ++k) {
      const double phi = 2.0 * M_PI * k / around;
      mesh.vertices_m.col(vertex(ring, k)) =
          Eigen::Vector3d(p.x() * std::cos(phi), p.x() * std::sin(phi), p.y());
    }
  }
  std::vector<Eigen::Vector3i> triangles;
  for (int k = 0; k < around; ++k) {
    triangles.emplace_back(0, vertex(0, k + 1), vertex(0, k));  // bottom fan, facing down
    for (int ring = 0; ring + 1 < rings; ++ring) {
      triangles.emplace_back(vertex(ring, k), vertex(ring, k + 1), vertex(ring + 1, k + 1));
      triangles.emplace_back(vertex(ring, k), vertex(ring + 1, k + 1), vertex(ring + 1, k));
    }
    triangles.emplace_back(1, vertex(rings - 1, k), vertex(rings - 1, k + 1));  // top fan
  }
  mesh.triangles.resize(3, static_cast<Eigen::Index>(triangles.size()));
  for (size_t f = 0; f < triangles.size(); ++f) mesh.triangles.col(f) = triangles[f];
  return mesh;
}

// Quarter or half arcs of radius r about (ρ_c, z_c) from angle a0 to a1 (from +ρ, towards +z),
// `pieces` pieces, end points included; appended to *profile.
void AddArc(double rho_c, double z_c, double r, double a0, double a1, int pieces,
            std::vector<Eigen::Vector2d>* profile) {
  for (int i = 0; i <= pieces; ++i) {
    const double a = a0 + (a1 - a0) * i / pieces;
    profile->emplace_back(rho_c + r * std::cos(a), z_c + r * std::sin(a));
  }
}

TriangleMesh MakeBoxMesh(const Eigen::Vector3d& h) {
  TriangleMesh mesh;
  mesh.vertices_m.resize(3, 8);
  for (int i = 0; i < 8; ++i)
    mesh.vertices_m.col(i) = Eigen::Vector3d((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(),
                                             (i & 4) ? h.z() : -h.z());
  // Two triangles per face, counter-clockwise seen from outside.
  const int faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  mesh.triangles.resize(3, 12);
  for (int f = 0; f < 6; ++f) {
    mesh.triangles.col(2 * f) = Eigen::Vector3i(faces[f][0], faces[f][1], faces[f][2]);
    mesh.triangles.col(2 * f + 1) = Eigen::Vector3i(faces[f][0], faces[f][2], faces[f][3]);
  }
  return mesh;
}

}  // namespace

TriangleMesh MakeShapeMesh(const ToolShape& shape, int segments) {
  if (segments < 8) throw std::invalid_argument("MakeShapeMesh: segments must be >= 8");
  const double r = shape.radius_m;
  const double half = 0.5 * shape.length_m;
  std::vector<Eigen::Vector2d> profile;
  switch (shape.kind) {
    case ToolShape::Kind::kMesh:
      return shape.mesh;
    case ToolShape::Kind::kBox:
      if (!(shape.half_extents_m.minCoeff() > 0.0))
        throw std::invalid_argument("MakeShapeMesh: box half extents must be > 0");
      return MakeBoxMesh(shape.half_extents_m);
    case ToolShape::Kind::kSphere:
    case ToolShape::Kind::kCapsule:
      if (!(r > 0.0) || !(half >= 0.0))
        throw std::invalid_argument("MakeShapeMesh: sphere or capsule radius must be > 0");
      AddArc(0.0, -half, r, -0.5 * M_PI, 0.0, segments / 4, &profile);  // bottom cap
      AddArc(0.0, half, r, 0.0, 0.5 * M_PI, segments / 4, &profile);    // top cap
      return MakeRevolutionMesh(profile, segments);
    case ToolShape::Kind::kCylinder: {
      const double e = shape.edge_radius_m;
      if (!(r > 0.0) || !(half > 0.0))
        throw std::invalid_argument("MakeShapeMesh: cylinder radius and length must be > 0");
      profile.emplace_back(0.0, -half);
      if (e > 0.0) {
        AddArc(r - e, -half + e, e, -0.5 * M_PI, 0.0, segments / 4, &profile);
        AddArc(r - e, half - e, e, 0.0, 0.5 * M_PI, segments / 4, &profile);
      } else {
        profile.emplace_back(r, -half);
        profile.emplace_back(r, half);
      }
      profile.emplace_back(0.0, half);
      return MakeRevolutionMesh(profile, segments);
    }
  }
  throw std::invalid_argument("MakeShapeMesh: unknown shape");
}

}  // namespace hapsim
