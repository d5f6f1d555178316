#include "core/tool_shape.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace hapsim {
namespace {

void Require(bool condition, const std::string& message) {
  if (!condition) throw std::invalid_argument("CalcMassProperties: " + message);
}

// Uniform solid sphere: m = ρ (4/3) π r³, I = (2/5) m r² on every axis.
MassProperties CalcSphere(double r, double density) {
  MassProperties props;
  props.mass_kg = density * 4.0 / 3.0 * M_PI * r * r * r;
  props.inertia_com_kg_m2 = Eigen::Matrix3d::Identity() * (0.4 * props.mass_kg * r * r);
  return props;
}

// Solid cylinder of radius r and height h along z: m = ρ π r² h,
// I_zz = m r²/2, I_xx = I_yy = m (3 r² + h²)/12.
MassProperties CalcCylinder(double r, double h, double density) {
  MassProperties props;
  const double m = density * M_PI * r * r * h;
  props.mass_kg = m;
  const double lateral = m * (3.0 * r * r + h * h) / 12.0;
  props.inertia_com_kg_m2.diagonal() << lateral, lateral, 0.5 * m * r * r;
  return props;
}

// Cylinder of radius r and height h with its rim rounded by radius e (0 < e ≤ min(r, h/2)).
// The solid is a stack of disks of radius S(z) along z; a disk of mass dm = ρ π S² dz has
// I_zz = dm S²/2 and, moved to height z, I_xx = dm (S²/4 + z²). Over the straight part
// |z| ≤ h/2 − e, S = r; over each rounded band z = h/2 − e + e sin φ, S = r − e + e cos φ,
// dz = e cos φ dφ, φ ∈ [0, π/2], a smooth integrand integrated by composite Simpson (4096
// intervals: relative error ~1e-15; tests compare with the sphere and capsule closed forms).
MassProperties CalcRoundedCylinder(double r, double h, double e, double density) {
  const double h_straight = h - 2.0 * e;
  MassProperties props = CalcCylinder(r, h_straight, density);
  constexpr int kIntervals = 4096;
  const double step = 0.5 * M_PI / kIntervals;
  double mass = 0.0, i_zz = 0.0, i_xx = 0.0;
  for (int k = 0; k <= kIntervals; ++k) {
    const double weight = (k == 0 || k == kIntervals) ? 1.0 : (k % 2 == 1 ? 4.0 : 2.0);
    const double phi = k * step;
    const double S = r - e + e * std::cos(phi);
    const double z = 0.5 * h_straight + e * std::sin(phi);
    const double dm = density * M_PI * S * S * e * std::cos(phi);  // per dφ
    mass += weight * dm;
    i_zz += weight * dm * 0.5 * S * S;
    i_xx += weight * dm * (0.25 * S * S + z * z);
  }
  const double both_bands = 2.0 * step / 3.0;  // two bands × Simpson's step/3
  props.mass_kg += both_bands * mass;
  props.inertia_com_kg_m2.diagonal() += both_bands * Eigen::Vector3d(i_xx, i_xx, i_zz);
  return props;
}

// Capsule = cylinder (radius r, height h) + two hemispheres. Each hemisphere (mass m_h) has
// I = (2/5) m_h r² about any axis through the centre of its flat face, its centre of mass at 3r/8
// from that face; moved to the capsule centre (distance h/2 + 3r/8) by the parallel-axis theorem:
// I_xx,h = m_h (2r²/5 + h²/4 + 3hr/8), I_zz,h = (2/5) m_h r².
MassProperties CalcCapsule(double r, double h, double density) {
  MassProperties props = CalcCylinder(r, h, density);
  const double m_caps = density * 4.0 / 3.0 * M_PI * r * r * r;  // both hemispheres
  props.mass_kg += m_caps;
  const double lateral = m_caps * (0.4 * r * r + 0.25 * h * h + 0.375 * h * r);
  props.inertia_com_kg_m2.diagonal() += Eigen::Vector3d(lateral, lateral, 0.4 * m_caps * r * r);
  return props;
}

// Box of half extents (a, b, c): m = 8 ρ a b c, I_xx = m (b² + c²)/3, etc.
MassProperties CalcBox(const Eigen::Vector3d& e, double density) {
  MassProperties props;
  const double m = 8.0 * density * e.x() * e.y() * e.z();
  props.mass_kg = m;
  const Eigen::Vector3d sq = e.cwiseProduct(e);
  props.inertia_com_kg_m2.diagonal() << m * (sq.y() + sq.z()) / 3.0, m * (sq.x() + sq.z()) / 3.0,
      m * (sq.x() + sq.y()) / 3.0;
  return props;
}

// Eberly's subexpressions for one coordinate w of the triangle's three vertices.
struct Subexpressions {
  double f1, f2, f3, g0, g1, g2;
};
Subexpressions CalcSubexpressions(double w0, double w1, double w2) {
  Subexpressions s;
  const double temp0 = w0 + w1;
  s.f1 = temp0 + w2;
  const double temp1 = w0 * w0;
  const double temp2 = temp1 + w1 * temp0;
  s.f2 = temp2 + w2 * s.f1;
  s.f3 = w0 * temp1 + w1 * temp2 + w2 * s.f2;
  s.g0 = s.f2 + w0 * (s.f1 + w0);
  s.g1 = s.f2 + w1 * (s.f1 + w1);
  s.g2 = s.f2 + w2 * (s.f1 + w2);
  return s;
}

// Closed polyhedron (Eberly 2002, "Polyhedral Mass Properties (Revisited)"): the volume
// integrals of 1, x, y, z, x², y², z², xy, yz, zx become, by the divergence theorem, sums over
// the faces of polynomials in the vertex coordinates. Coordinates are taken relative to the
// vertex mean to keep the cubic terms well conditioned far from the origin.
MassProperties CalcMesh(const TriangleMesh& mesh, double density) {
  std::string defect;
  const int bad = FindOpenOrMisorientedTriangle(mesh, &defect);
  Require(bad < 0, "mesh is not closed and consistently oriented: " + defect);
  const Eigen::Vector3d origin = mesh.vertices_m.rowwise().mean();
  std::array<double, 10> integral{};
  for (Eigen::Index f = 0; f < mesh.triangles.cols(); ++f) {
    const Eigen::Vector3d p0 = mesh.vertices_m.col(mesh.triangles(0, f)) - origin;
    const Eigen::Vector3d p1 = mesh.vertices_m.col(mesh.triangles(1, f)) - origin;
    const Eigen::Vector3d p2 = mesh.vertices_m.col(mesh.triangles(2, f)) - origin;
    const Eigen::Vector3d d = (p1 - p0).cross(p2 - p0);
    const Subexpressions x = CalcSubexpressions(p0.x(), p1.x(), p2.x());
    const Subexpressions y = CalcSubexpressions(p0.y(), p1.y(), p2.y());
    const Subexpressions z = CalcSubexpressions(p0.z(), p1.z(), p2.z());
    integral[0] += d.x() * x.f1;
    integral[1] += d.x() * x.f2;
    integral[2] += d.y() * y.f2;
    integral[3] += d.z() * z.f2;
    integral[4] += d.x() * x.f3;
    integral[5] += d.y() * y.f3;
    integral[6] += d.z() * z.f3;
    integral[7] += d.x() * (p0.y() * x.g0 + p1.y() * x.g1 + p2.y() * x.g2);
    integral[8] += d.y() * (p0.z() * y.g0 + p1.z() * y.g1 + p2.z() * y.g2);
    integral[9] += d.z() * (p0.x() * z.g0 + p1.x() * z.g1 + p2.x() * z.g2);
  }
  const std::array<double, 10> scale = {1.0 / 6,  1.0 / 24, 1.0 / 24,  1.0 / 24,  1.0 / 60,
                                        1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (int i = 0; i < 10; ++i) integral[i] *= scale[i] * density;
  const double m = integral[0];
  Require(m > 0.0, "mesh encloses no positive volume (volume " +
                       std::to_string(integral[0] / density) + " m^3)");
  const Eigen::Vector3d c(integral[1] / m, integral[2] / m, integral[3] / m);
  MassProperties props;
  props.mass_kg = m;
  props.com_m = origin + c;
  Eigen::Matrix3d& I = props.inertia_com_kg_m2;
  I(0, 0) = integral[5] + integral[6] - m * (c.y() * c.y() + c.z() * c.z());
  I(1, 1) = integral[4] + integral[6] - m * (c.z() * c.z() + c.x() * c.x());
  I(2, 2) = integral[4] + integral[5] - m * (c.x() * c.x() + c.y() * c.y());
  I(0, 1) = I(1, 0) = -(integral[7] - m * c.x() * c.y());
  I(1, 2) = I(2, 1) = -(integral[8] - m * c.y() * c.z());
  I(0, 2) = I(2, 0) = -(integral[9] - m * c.z() * c.x());
  return props;
}

}  // namespace

MassProperties CalcMassProperties(const ToolShape& shape, double density_kg_m3) {
  Require(std::isfinite(density_kg_m3) && density_kg_m3 > 0.0, "density must be positive");
  switch (shape.kind) {
    case ToolShape::Kind::kSphere:
      Require(shape.radius_m > 0.0, "sphere radius must be positive");
      return CalcSphere(shape.radius_m, density_kg_m3);
    case ToolShape::Kind::kCapsule:
      Require(shape.radius_m > 0.0 && shape.length_m >= 0.0,
              "capsule needs radius > 0 and length >= 0");
      return CalcCapsule(shape.radius_m, shape.length_m, density_kg_m3);
    case ToolShape::Kind::kCylinder:
      Require(shape.radius_m > 0.0 && shape.length_m > 0.0,
              "cylinder needs radius > 0 and length > 0");
      Require(shape.edge_radius_m >= 0.0 && shape.edge_radius_m <= shape.radius_m &&
                  shape.edge_radius_m <= 0.5 * shape.length_m,
              "cylinder edge radius must be in [0, min(radius, length/2)]");
      if (shape.edge_radius_m > 0.0)
        return CalcRoundedCylinder(shape.radius_m, shape.length_m, shape.edge_radius_m,
                                   density_kg_m3);
      return CalcCylinder(shape.radius_m, shape.length_m, density_kg_m3);
    case ToolShape::Kind::kBox:
      Require((shape.half_extents_m.array() > 0.0).all(), "box half extents must be positive");
      return CalcBox(shape.half_extents_m, density_kg_m3);
    case ToolShape::Kind::kMesh:
      return CalcMesh(shape.mesh, density_kg_m3);
  }
  throw std::invalid_argument("CalcMassProperties: unknown shape kind");
}

int FindOpenOrMisorientedTriangle(const TriangleMesh& mesh, std::string* message) {
  const Eigen::Index num_vertices = mesh.vertices_m.cols();
  const Eigen::Index num_triangles = mesh.triangles.cols();
  if (num_triangles == 0) {
    *message = "the mesh has no triangles";
    return 0;
  }
  // Directed edges (a, b, triangle), sorted so that a repeated or missing twin is found by search.
  std::vector<std::array<int, 3>> edges;
  edges.reserve(3 * num_triangles);
  for (Eigen::Index f = 0; f < num_triangles; ++f) {
    const int t = static_cast<int>(f);
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.triangles(k, f);
      const int b = mesh.triangles((k + 1) % 3, f);
      if (a < 0 || a >= num_vertices) {
        *message = "triangle " + std::to_string(t) + " has vertex index " + std::to_string(a) +
                   " out of range [0, " + std::to_string(num_vertices) + ")";
        return t;
      }
      if (a == b) {
        *message = "triangle " + std::to_string(t) + " repeats vertex " + std::to_string(a);
        return t;
      }
      edges.push_back({a, b, t});
    }
  }
  std::sort(edges.begin(), edges.end());
  auto same_edge = [](const std::array<int, 3>& e, const std::array<int, 3>& g) {
    return e[0] == g[0] && e[1] == g[1];
  };
  for (size_t i = 0; i < edges.size(); ++i) {
    const std::array<int, 3>& e = edges[i];
    const std::string edge = "edge (" + std::to_string(e[0]) + ", " + std::to_string(e[1]) + ")";
    if (i + 1 < edges.size() && same_edge(e, edges[i + 1])) {
      *message = edge + " is used in the same direction by triangles " + std::to_string(e[2]) +
                 " and " + std::to_string(edges[i + 1][2]) +
                 " (inconsistent orientation or non-manifold)";
      return edges[i + 1][2];
    }
    const std::array<int, 3> twin = {e[1], e[0], -1};
    const auto it = std::lower_bound(edges.begin(), edges.end(), twin);
    if (it == edges.end() || !same_edge(*it, twin)) {
      *message = edge + " of triangle " + std::to_string(e[2]) +
                 " has no opposite edge (the mesh is not closed)";
      return e[2];
    }
  }
  return -1;
}

double CalcSignedVolume_m3(const TriangleMesh& mesh) {
  double six_volume = 0.0;
  for (Eigen::Index f = 0; f < mesh.triangles.cols(); ++f) {
    const Eigen::Vector3d a = mesh.vertices_m.col(mesh.triangles(0, f));
    const Eigen::Vector3d b = mesh.vertices_m.col(mesh.triangles(1, f));
    const Eigen::Vector3d c = mesh.vertices_m.col(mesh.triangles(2, f));
    six_volume += a.dot(b.cross(c));
  }
  return six_volume / 6.0;
}

}  // namespace hapsim
