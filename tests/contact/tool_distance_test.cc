// Signed distance to the tool (contact/tool_distance.h) against closed-form signed distance
// functions written independently of the implementation's case analysis, finite-difference
// gradients, and triangulated versions of the same primitives.

#include "contact/tool_distance.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

namespace hapsim::contact {
namespace {

using Eigen::Vector3d;

// Distances are O(1 cm); these are round-off levels for such values.
constexpr double kExactTolerance_m = 1e-12;
// Central differences with step kStep_m have truncation error O(h²·curvature) ≈ 1e-10 and
// round-off error O(ε·d/h) ≈ 1e-11 here; a random point lies within kStep_m of the medial axis
// (where the gradient jumps) with probability ~1e-5, and with the fixed seed none does. Across
// the boundary between a face's region and an edge's or corner's region outside the shape, the
// distance is C¹ but its curvature jumps by up to 1/|φ|, so a difference straddling it errs by up
// to h/|φ|: the tolerance includes that term.
constexpr double kStep_m = 1e-7;
constexpr double kGradientTolerance = 1e-6;

// Closed-form signed distances (the "max/length" forms, e.g. Quilez's list of SDFs).
double BoxSdf(const Vector3d& h, const Vector3d& p) {
  const Vector3d q = p.cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}
double CylinderSdf(double r, double length, const Vector3d& p) {
  const Eigen::Vector2d d(std::hypot(p.x(), p.y()) - r, std::abs(p.z()) - 0.5 * length);
  return std::min(d.maxCoeff(), 0.0) + d.cwiseMax(0.0).norm();
}
double CapsuleSdf(double r, double length, const Vector3d& p) {
  const double z = std::max(std::abs(p.z()) - 0.5 * length, 0.0);
  return std::sqrt(p.x() * p.x() + p.y() * p.y() + z * z) - r;
}

class Points {
 public:
  explicit Points(unsigned seed) : engine_(seed) {}
  // Uniform in [−extent, extent] per axis.
  Vector3d In(const Vector3d& extent) {
    return Vector3d(u_(engine_), u_(engine_), u_(engine_)).cwiseProduct(extent);
  }

 private:
  std::mt19937 engine_;
  std::uniform_real_distribution<double> u_{-1.0, 1.0};
};

// p = closest + φ n with |n| = 1, for points inside as well as outside.
void ExpectSelfConsistent(const ToolDistance& d, const Vector3d& p) {
  EXPECT_NEAR(d.normal_T.norm(), 1.0, 1e-12);
  EXPECT_LT((d.closest_T_m + d.distance_m * d.normal_T - p).norm(), kExactTolerance_m);
}

template <typename DistanceFunction>
void ExpectNormalIsGradient(const DistanceFunction& phi, const Vector3d& p) {
  Vector3d gradient;
  for (int axis = 0; axis < 3; ++axis) {
    const Vector3d step = kStep_m * Vector3d::Unit(axis);
    gradient[axis] = (phi(p + step).distance_m - phi(p - step).distance_m) / (2.0 * kStep_m);
  }
  const double tolerance = kGradientTolerance + kStep_m / std::abs(phi(p).distance_m);
  EXPECT_LT((gradient - phi(p).normal_T).norm(), tolerance) << p.transpose();
}

// Random points in a box around the shape: half of them inside, half outside, is asserted.
template <typename DistanceFunction, typename Sdf>
void CheckAgainstSdf(const DistanceFunction& phi, const Sdf& sdf, const Vector3d& extent) {
  Points points(7);
  int inside = 0, outside = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p = points.In(extent);
    const ToolDistance d = phi(p);
    ASSERT_NEAR(d.distance_m, sdf(p), kExactTolerance_m) << p.transpose();
    ExpectSelfConsistent(d, p);
    ExpectNormalIsGradient(phi, p);
    (d.distance_m < 0.0 ? inside : outside)++;
  }
  EXPECT_GT(inside, 200);
  EXPECT_GT(outside, 200);
}

TEST(ToolDistanceTest, SphereMatchesClosedForm) {
  const double r = 0.01;
  CheckAgainstSdf([&](const Vector3d& p) { return CalcSphereDistance(r, p); },
                  [&](const Vector3d& p) { return p.norm() - r; }, Vector3d::Constant(0.015));
}

TEST(ToolDistanceTest, CapsuleMatchesClosedForm) {
  const double r = 0.004, length = 0.03;
  CheckAgainstSdf([&](const Vector3d& p) { return CalcCapsuleDistance(r, length, p); },
                  [&](const Vector3d& p) { return CapsuleSdf(r, length, p); },
                  Vector3d(0.007, 0.007, 0.022));
}

TEST(ToolDistanceTest, CylinderMatchesClosedFormOnSideCapsAndRim) {
  const double r = 0.006, length = 0.02;
  CheckAgainstSdf([&](const Vector3d& p) { return CalcCylinderDistance(r, length, p); },
                  [&](const Vector3d& p) { return CylinderSdf(r, length, p); },
                  Vector3d(0.01, 0.01, 0.015));
  // The rim region (ρ > r and |z| > L/2) is where the normal is neither radial nor axial.
  const ToolDistance rim = CalcCylinderDistance(r, length, Vector3d(r + 0.003, 0.0, 0.014));
  EXPECT_NEAR(rim.distance_m, 0.005, kExactTolerance_m);
  EXPECT_LT((rim.normal_T - Vector3d(0.6, 0.0, 0.8)).norm(), 1e-12);
}

// The rounded-rim cylinder against Quilez's "rounded cylinder" SDF (a rounded rectangle in the
// (ρ, z) half-plane), and with edge radius = radius against the capsule it then is.
TEST(ToolDistanceTest, RoundedCylinderMatchesClosedForm) {
  const double r = 0.006, length = 0.02, e = 0.002;
  const auto rounded_sdf = [&](const Vector3d& p) {
    const Eigen::Vector2d d(std::hypot(p.x(), p.y()) - (r - e), std::abs(p.z()) - 0.5 * length + e);
    return std::min(d.maxCoeff(), 0.0) + d.cwiseMax(0.0).norm() - e;
  };
  CheckAgainstSdf([&](const Vector3d& p) { return CalcCylinderDistance(r, length, p, e); },
                  rounded_sdf, Vector3d(0.01, 0.01, 0.015));
  CheckAgainstSdf([&](const Vector3d& p) { return CalcCylinderDistance(r, length, p, r); },
                  [&](const Vector3d& p) { return CapsuleSdf(r, length - 2.0 * r, p); },
                  Vector3d(0.009, 0.009, 0.015));
}

TEST(ToolDistanceTest, BoxMatchesClosedForm) {
  const Vector3d h(0.01, 0.004, 0.007);
  CheckAgainstSdf([&](const Vector3d& p) { return CalcBoxDistance(h, p); },
                  [&](const Vector3d& p) { return BoxSdf(h, p); }, 1.5 * h);
}

// Triangulated shapes, oriented outward by the sign of the normal against the centroid (all the
// shapes here are convex and contain the origin).
TriangleMesh MakeConvexMesh(const Matrix3Xd& vertices, const std::vector<Eigen::Vector3i>& tris) {
  TriangleMesh mesh;
  mesh.vertices_m = vertices;
  mesh.triangles.resize(3, static_cast<Eigen::Index>(tris.size()));
  for (size_t f = 0; f < tris.size(); ++f) {
    Eigen::Vector3i t = tris[f];
    const Vector3d a = vertices.col(t[0]), b = vertices.col(t[1]), c = vertices.col(t[2]);
    if ((b - a).cross(c - a).dot(a + b + c) < 0.0) std::swap(t[1], t[2]);
    mesh.triangles.col(static_cast<Eigen::Index>(f)) = t;
  }
  return mesh;
}

TriangleMesh MakeBoxMesh(const Vector3d& h) {
  Matrix3Xd vertices(3, 8);
  for (int c = 0; c < 8; ++c)
    vertices.col(c) =
        Vector3d((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1).cwiseProduct(h);
  // Each face: the 4 corners with one bit fixed, split along a diagonal.
  std::vector<Eigen::Vector3i> tris;
  for (int bit : {1, 2, 4})
    for (int value : {0, bit}) {
      std::vector<int> quad;
      for (int c = 0; c < 8; ++c)
        if ((c & bit) == value) quad.push_back(c);  // ordered so quad[0], quad[3] are opposite
      tris.emplace_back(quad[0], quad[1], quad[3]);
      tris.emplace_back(quad[0], quad[3], quad[2]);
    }
  return MakeConvexMesh(vertices, tris);
}

// UV sphere: 2 poles and (rings − 1) × segments vertices on the sphere.
TriangleMesh MakeSphereMesh(double r, int rings, int segments) {
  Matrix3Xd vertices(3, 2 + (rings - 1) * segments);
  vertices.col(0) = Vector3d(0, 0, r);
  vertices.col(1) = Vector3d(0, 0, -r);
  auto index = [&](int ring, int s) { return 2 + (ring - 1) * segments + (s % segments); };
  for (int ring = 1; ring < rings; ++ring)
    for (int s = 0; s < segments; ++s) {
      const double theta = M_PI * ring / rings, psi = 2.0 * M_PI * s / segments;
      vertices.col(index(ring, s)) = r * Vector3d(std::sin(theta) * std::cos(psi),
                                                  std::sin(theta) * std::sin(psi), std::cos(theta));
    }
  std::vector<Eigen::Vector3i> tris;
  for (int s = 0; s < segments; ++s) {
    tris.emplace_back(0, index(1, s), index(1, s + 1));
    tris.emplace_back(1, index(rings - 1, s), index(rings - 1, s + 1));
    for (int ring = 1; ring + 1 < rings; ++ring) {
      tris.emplace_back(index(ring, s), index(ring + 1, s), index(ring + 1, s + 1));
      tris.emplace_back(index(ring, s), index(ring + 1, s + 1), index(ring, s + 1));
    }
  }
  return MakeConvexMesh(vertices, tris);
}

// Prism over a regular n-gon inscribed in the circle of radius r; caps fanned from their centres.
TriangleMesh MakeCylinderMesh(double r, double length, int n) {
  Matrix3Xd vertices(3, 2 * n + 2);
  for (int rim = 0; rim < 2; ++rim)
    for (int k = 0; k < n; ++k)
      vertices.col(rim * n + k) = Vector3d(r * std::cos(2 * M_PI * k / n),
                                           r * std::sin(2 * M_PI * k / n), (rim - 0.5) * length);
  vertices.col(2 * n) = Vector3d(0, 0, -0.5 * length);
  vertices.col(2 * n + 1) = Vector3d(0, 0, 0.5 * length);
  std::vector<Eigen::Vector3i> tris;
  for (int k = 0; k < n; ++k) {
    const int k1 = (k + 1) % n;
    tris.emplace_back(k, k1, n + k1);
    tris.emplace_back(k, n + k1, n + k);
    tris.emplace_back(2 * n, k, k1);
    tris.emplace_back(2 * n + 1, n + k, n + k1);
  }
  return MakeConvexMesh(vertices, tris);
}

TEST(ToolDistanceTest, BoxMeshEqualsBoxPrimitive) {
  const Vector3d h(0.01, 0.004, 0.007);
  const MeshDistanceField mesh(MakeBoxMesh(h));
  Points points(11);
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p = points.In(1.5 * h);
    const ToolDistance expected = CalcBoxDistance(h, p), actual = mesh.Calc(p);
    ASSERT_NEAR(actual.distance_m, expected.distance_m, kExactTolerance_m) << p.transpose();
    EXPECT_LT((actual.closest_T_m - expected.closest_T_m).norm(), kExactTolerance_m);
    EXPECT_LT((actual.normal_T - expected.normal_T).norm(), 1e-9);
  }
}

// An inscribed polyhedron P of a convex body B satisfies sdf_B ≤ sdf_P ≤ sdf_B + δ, δ the largest
// distance from ∂B to P (r − min face-plane distance); the bounds also fix the sign wherever
// |sdf_B| > δ, so they test the pseudonormal sign at faces, edges and vertices.
template <typename Exact>
void CheckInscribedMesh(const TriangleMesh& mesh, const Exact& exact, const Vector3d& extent,
                        double bound_m) {
  const MeshDistanceField field(mesh);
  Points points(13);
  for (int i = 0; i < 3000; ++i) {
    const Vector3d p = points.In(extent);
    const double difference = field.Calc(p).distance_m - exact(p);
    ASSERT_GE(difference, -kExactTolerance_m) << p.transpose();
    ASSERT_LE(difference, bound_m + kExactTolerance_m) << p.transpose();
    ExpectSelfConsistent(field.Calc(p), p);
    // Outside a convex polyhedron the distance is C¹ (no medial axis); inside, every pair of
    // neighbouring faces adds a kink, so the gradient is checked outside only.
    if (field.Calc(p).distance_m > 10.0 * kStep_m)
      ExpectNormalIsGradient([&](const Vector3d& q) { return field.Calc(q); }, p);
  }
}

double CalcInscribedBound(const TriangleMesh& mesh, double r) {
  double min_plane_m = r;
  for (Eigen::Index f = 0; f < mesh.triangles.cols(); ++f) {
    const Vector3d a = mesh.vertices_m.col(mesh.triangles(0, f));
    const Vector3d n = (mesh.vertices_m.col(mesh.triangles(1, f)) - a)
                           .cross(mesh.vertices_m.col(mesh.triangles(2, f)) - a)
                           .normalized();
    min_plane_m = std::min(min_plane_m, n.dot(a));
  }
  return r - min_plane_m;
}

TEST(ToolDistanceTest, FineSphereMeshBracketsSphere) {
  const double r = 0.01;
  const TriangleMesh mesh = MakeSphereMesh(r, 24, 48);
  const double bound_m = CalcInscribedBound(mesh, r);
  EXPECT_LT(bound_m, 2e-4);  // a fine mesh: the bracket is tight
  CheckInscribedMesh(
      mesh, [&](const Vector3d& p) { return p.norm() - r; }, Vector3d::Constant(0.015), bound_m);
}

TEST(ToolDistanceTest, FineCylinderMeshBracketsCylinder) {
  const double r = 0.006, length = 0.02;
  const int n = 64;
  CheckInscribedMesh(
      MakeCylinderMesh(r, length, n), [&](const Vector3d& p) { return CylinderSdf(r, length, p); },
      Vector3d(0.01, 0.01, 0.015), r * (1.0 - std::cos(M_PI / n)));
}

TEST(ToolDistanceTest, RejectsOpenOrBadMeshes) {
  TriangleMesh open = MakeBoxMesh(Vector3d::Constant(0.01));
  open.triangles.conservativeResize(3, open.triangles.cols() - 1);
  EXPECT_THROW(MeshDistanceField{open}, std::invalid_argument);
  TriangleMesh out_of_range = MakeBoxMesh(Vector3d::Constant(0.01));
  out_of_range.triangles(0, 0) = 8;
  EXPECT_THROW(MeshDistanceField{out_of_range}, std::invalid_argument);
  EXPECT_THROW(MeshDistanceField{TriangleMesh{}}, std::invalid_argument);
  ToolShape sphere;
  sphere.radius_m = 0.0;
  EXPECT_THROW(ToolDistanceField{sphere}, std::invalid_argument);
}

// |p(s) − q(t)|² is convex in (s, t), so the Karush–Kuhn–Tucker conditions on [0, 1]² certify
// the minimum: ∂/∂s = d1·(p − q) is 0 inside, ≥ 0 at s = 0, ≤ 0 at s = 1; likewise t with −d2.
// A 101 × 101 grid of (s, t) never beats it. Random pairs, then parallel, crossing and point
// segments.
void ExpectClosestPointsOfSegments(const Vector3d& p1, const Vector3d& q1, const Vector3d& p2,
                                   const Vector3d& q2) {
  const SegmentPoints r = CalcClosestPointsOfSegments(p1, q1, p2, q2);
  const Vector3d d1 = q1 - p1, d2 = q2 - p2, offset = r.point1 - r.point2;
  ASSERT_GE(r.s, 0.0);
  ASSERT_LE(r.s, 1.0);
  ASSERT_GE(r.t, 0.0);
  ASSERT_LE(r.t, 1.0);
  EXPECT_LT((p1 + r.s * d1 - r.point1).norm(), kExactTolerance_m);
  EXPECT_LT((p2 + r.t * d2 - r.point2).norm(), kExactTolerance_m);
  // Gradient components are O(|d|·|offset|) ≤ (1 cm)²: round-off ≈ 1e-18.
  const double kkt_tolerance_m2 = 1e-15;
  const auto expect_stationary = [kkt_tolerance_m2](double parameter, double gradient) {
    if (parameter > 0.0) {
      EXPECT_LE(gradient, kkt_tolerance_m2) << parameter;
    }
    if (parameter < 1.0) {
      EXPECT_GE(gradient, -kkt_tolerance_m2) << parameter;
    }
  };
  expect_stationary(r.s, d1.dot(offset));
  expect_stationary(r.t, -d2.dot(offset));
  double grid_min_m = std::numeric_limits<double>::infinity();
  for (int i = 0; i <= 100; ++i)
    for (int j = 0; j <= 100; ++j)
      grid_min_m = std::min(grid_min_m, (p1 + 0.01 * i * d1 - p2 - 0.01 * j * d2).norm());
  EXPECT_LE(offset.norm(), grid_min_m + kExactTolerance_m);
}

TEST(ToolDistanceTest, ClosestPointsOfSegmentsSatisfyOptimality) {
  Points points(11);
  const Vector3d extent = Vector3d::Constant(0.01);
  for (int i = 0; i < 300; ++i)
    ExpectClosestPointsOfSegments(points.In(extent), points.In(extent), points.In(extent),
                                  points.In(extent));
  const Vector3d a(0.001, 0.002, 0.003), x(0.01, 0.0, 0.0), y(0.0, 0.01, 0.0);
  ExpectClosestPointsOfSegments(a, a + x, a + 0.5 * x + 0.002 * y, a + 2.0 * x + 0.002 * y);
  ExpectClosestPointsOfSegments(a, a + x, a + x + 0.002 * y, a + 0.002 * y);  // antiparallel
  ExpectClosestPointsOfSegments(a, a, a + y, a + x);                          // a point
  ExpectClosestPointsOfSegments(a, a + x, a + y, a + y);                      // a point
  ExpectClosestPointsOfSegments(a, a, a + y, a + y);                          // two points
  // Crossing at right angles 1 mm apart: the interior points (0.3, 0.6 of the way), exactly.
  const Vector3d up(0.0, 0.0, 0.001);
  const SegmentPoints crossing =
      CalcClosestPointsOfSegments(a - 0.3 * x, a + 0.7 * x, a + up - 0.6 * y, a + up + 0.4 * y);
  EXPECT_NEAR(crossing.s, 0.3, 1e-12);
  EXPECT_NEAR(crossing.t, 0.6, 1e-12);
  EXPECT_LT((crossing.point1 - a).norm(), kExactTolerance_m);
  EXPECT_LT((crossing.point2 - (a + up)).norm(), kExactTolerance_m);
}

TEST(ToolDistanceTest, FeaturesLieOnTheSurface) {
  ToolShape box;
  box.kind = ToolShape::Kind::kBox;
  box.half_extents_m = Vector3d(0.01, 0.004, 0.007);
  const ToolFeatures box_features = MakeToolFeatures(box);
  ASSERT_EQ(box_features.vertices_T_m.cols(), 8);
  ASSERT_EQ(box_features.edges.cols(), 12);
  double total_edge_length_m = 0.0;
  for (Eigen::Index e = 0; e < 12; ++e)
    total_edge_length_m += (box_features.vertices_T_m.col(box_features.edges(0, e)) -
                            box_features.vertices_T_m.col(box_features.edges(1, e)))
                               .norm();
  EXPECT_NEAR(total_edge_length_m, 8.0 * box.half_extents_m.sum(), 1e-15);

  ToolShape cylinder;
  cylinder.kind = ToolShape::Kind::kCylinder;
  cylinder.radius_m = 0.006;
  cylinder.length_m = 0.02;
  const ToolFeatures rim = MakeToolFeatures(cylinder, 16);
  ASSERT_EQ(rim.vertices_T_m.cols(), 32);
  ASSERT_EQ(rim.edges.cols(), 32);

  for (const auto& [shape, features] : {std::pair{box, box_features}, std::pair{cylinder, rim}}) {
    const ToolDistanceField field(shape);
    for (Eigen::Index i = 0; i < features.vertices_T_m.cols(); ++i) {
      EXPECT_NEAR(field.Calc(features.vertices_T_m.col(i)).distance_m, 0.0, 1e-15);
      // The cone axis points out of the tool: a step along it leaves the surface at once.
      EXPECT_GT(field.Calc(features.vertices_T_m.col(i) + 1e-4 * features.vertex_normals_T.col(i))
                    .distance_m,
                0.0);
    }
  }
  ToolShape sphere;
  sphere.radius_m = 0.01;
  EXPECT_EQ(MakeToolFeatures(sphere).vertices_T_m.cols(), 0);

  ToolShape mesh;
  mesh.kind = ToolShape::Kind::kMesh;
  mesh.mesh = MakeBoxMesh(box.half_extents_m);
  const ToolFeatures mesh_features = MakeToolFeatures(mesh);
  EXPECT_EQ(mesh_features.vertices_T_m.cols(), 8);
  EXPECT_EQ(mesh_features.edges.cols(), 18);  // 12 box edges + 6 face diagonals
  // Angle-weighted pseudonormal of a box corner: each face contributes π/2 → (±1, ±1, ±1)/√3.
  for (int c = 0; c < 8; ++c)
    EXPECT_LT((mesh_features.vertex_normals_T.col(c) - box_features.vertex_normals_T.col(c)).norm(),
              1e-12);
}

}  // namespace
}  // namespace hapsim::contact
