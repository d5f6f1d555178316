// GodObject (contact/god_object.h) against closed-form positions and forces: free space, a flat
// plane, a 1 mm plate at 1 m/s, a concave corner and wedge, the two steps round a convex edge,
// the friction sawtooth, force shading over a roof ridge, a moving plate, the bump texture, an
// allocation-free step, and the AABB tree against brute force.

#include "contact/god_object.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "contact/tool_distance.h"
#include "tests/allocation_counter.h"

namespace hapsim::contact {
namespace {

using Eigen::Vector3d;

constexpr double kPi = 3.14159265358979323846;
constexpr double kStiffness = 1000.0;  // N/m
constexpr double kEpsilon = 1e-9;      // the default surface epsilon, m
// Positions are sums and products of a few millimetre-sized terms: round-off is ~1e-18 m; the
// god-object is placed ε = 1e-9 m above its planes, which the expected values include. 1e-12 m
// is a thousand times below ε, so a missed ε (or a wrong plane) fails.
constexpr double kPosition_m = 1e-12;
constexpr double kForce_N = kStiffness * kPosition_m;

// Orients every triangle so that its normal (b − a) × (c − a) points along outward(centroid).
TriangleMesh MakeMesh(const std::vector<Vector3d>& vertices,
                      const std::vector<Eigen::Vector3i>& triangles,
                      const std::function<Vector3d(const Vector3d&)>& outward) {
  TriangleMesh mesh;
  mesh.vertices_m.resize(3, vertices.size());
  for (size_t i = 0; i < vertices.size(); ++i) mesh.vertices_m.col(i) = vertices[i];
  mesh.triangles.resize(3, triangles.size());
  for (size_t f = 0; f < triangles.size(); ++f) {
    Eigen::Vector3i t = triangles[f];
    const Vector3d a = vertices[t(0)], b = vertices[t(1)], c = vertices[t(2)];
    if ((b - a).cross(c - a).dot(outward((a + b + c) / 3.0)) < 0.0) std::swap(t(1), t(2));
    mesh.triangles.col(f) = t;
  }
  return mesh;
}

// Closed box [lo, hi], 12 triangles, outward.
TriangleMesh MakeBox(const Vector3d& lo, const Vector3d& hi) {
  std::vector<Vector3d> v;
  for (int i = 0; i < 8; ++i)
    v.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  const std::vector<Eigen::Vector3i> t = {{0, 1, 3}, {0, 3, 2}, {4, 5, 7}, {4, 7, 6},
                                          {0, 1, 5}, {0, 5, 4}, {2, 3, 7}, {2, 7, 6},
                                          {0, 2, 6}, {0, 6, 4}, {1, 3, 7}, {1, 7, 5}};
  const Vector3d centre = (lo + hi) / 2.0;
  return MakeMesh(v, t, [&](const Vector3d& p) {
    const Vector3d d = (p - centre).cwiseQuotient(hi - lo);
    int axis;
    d.cwiseAbs().maxCoeff(&axis);
    return Vector3d(Vector3d::Unit(axis) * d(axis));
  });
}

// Quad (4 corners, in order round it) as two triangles facing `normal`.
TriangleMesh MakeQuad(const Vector3d& p0, const Vector3d& p1, const Vector3d& p2,
                      const Vector3d& p3, const Vector3d& normal) {
  return MakeMesh({p0, p1, p2, p3}, {{0, 1, 2}, {0, 2, 3}},
                  [&](const Vector3d&) { return normal; });
}

// Height field z = h(x, y) over [−size/2, size/2]², n x n cells, 2 n² triangles facing +z.
TriangleMesh MakeHeightField(int n, double size_m, const std::function<double(double, double)>& h) {
  std::vector<Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = size_m * (i / static_cast<double>(n) - 0.5);
      const double y = size_m * (j / static_cast<double>(n) - 0.5);
      v.emplace_back(x, y, h(x, y));
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      t.emplace_back(a, a + 1, a + n + 2);
      t.emplace_back(a, a + n + 2, a + n + 1);
    }
  }
  return MakeMesh(v, t, [](const Vector3d&) { return Vector3d::UnitZ(); });
}

// A roof ridge along y at the origin: face A for x < 0 with normal (−sin α, 0, cos α), face B
// for x > 0 with normal (sin α, 0, cos α), each a rectangle width_m down the slope and 2 half_m
// along y, sharing the ridge vertices. Exterior dihedral angle 2α.
TriangleMesh MakeRoof(double alpha, double width_m, double half_m) {
  const Vector3d down_a(-std::cos(alpha), 0.0, -std::sin(alpha));
  const Vector3d down_b(std::cos(alpha), 0.0, -std::sin(alpha));
  const Vector3d y = half_m * Vector3d::UnitY();
  const std::vector<Vector3d> v = {-y,
                                   y,
                                   width_m * down_a - y,
                                   width_m * down_a + y,
                                   width_m * down_b - y,
                                   width_m * down_b + y};
  return MakeMesh(v, {{0, 2, 3}, {0, 3, 1}, {0, 4, 5}, {0, 5, 1}}, [](const Vector3d& p) {
    return Vector3d(p.x() < 0.0 ? -1.0 : 1.0, 0.0, 10.0);  // up, leaning away from the ridge
  });
}

GodObjectParams Params(double radius_m = 0.0) {
  GodObjectParams p;
  p.stiffness_N_m = kStiffness;
  p.proxy_radius_m = radius_m;
  return p;
}

double Angle(const Vector3d& a, const Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

TEST(GodObject, RejectsBadParametersAndMeshes) {
  const auto make = [](const std::function<void(GodObjectParams*)>& edit) {
    GodObjectParams p = Params();
    edit(&p);
    return GodObject(p);
  };
  EXPECT_THROW(make([](GodObjectParams* p) { p->stiffness_N_m = 0.0; }), std::invalid_argument);
  EXPECT_THROW(make([](GodObjectParams* p) { p->proxy_radius_m = -1e-3; }), std::invalid_argument);
  EXPECT_THROW(make([](GodObjectParams* p) { p->surface_epsilon_m = 0.0; }), std::invalid_argument);
  EXPECT_THROW(make([](GodObjectParams* p) { p->static_friction = -0.1; }), std::invalid_argument);
  EXPECT_THROW(make([](GodObjectParams* p) {
                 p->static_friction = 0.3;
                 p->dynamic_friction = 0.5;
               }),
               std::invalid_argument);
  EXPECT_THROW(make([](GodObjectParams* p) {
                 p->texture_amplitude_m = 1e-4;
                 p->texture_wavelength_m = 0.0;
               }),
               std::invalid_argument);
  EXPECT_NO_THROW(make([](GodObjectParams*) {}));

  GodObject god(Params());
  TriangleMesh bad = MakeBox(Vector3d::Zero(), Vector3d::Ones());
  bad.triangles(1, 3) = 8;
  EXPECT_THROW(god.AddMesh(bad, Eigen::Isometry3d::Identity()), std::invalid_argument);
  EXPECT_THROW(god.AddMesh(TriangleMesh{}, Eigen::Isometry3d::Identity()), std::invalid_argument);
  const int id =
      god.AddMesh(MakeBox(Vector3d::Zero(), Vector3d::Ones()), Eigen::Isometry3d::Identity());
  EXPECT_THROW(god.SetMeshPose(id + 1, Eigen::Isometry3d::Identity()), std::invalid_argument);
  EXPECT_THROW(god.SetMeshVertices(-1, Matrix3Xd::Zero(3, 8)), std::invalid_argument);
  EXPECT_THROW(god.SetMeshVertices(id, Matrix3Xd::Zero(3, 7)), std::invalid_argument);
}

TEST(GodObject, FreeSpaceProxyIsTheHip) {
  GodObject god(Params(1e-3));
  god.AddMesh(MakeBox(Vector3d(-0.1, -0.1, -0.2), Vector3d(0.1, 0.1, -0.1)),
              Eigen::Isometry3d::Identity());
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.1, 0.1);
  for (int i = 0; i < 200; ++i) {
    const Vector3d hip(u(rng), u(rng), 0.05 + 0.5 * u(rng));  // above the box (z > −0.1 + r)
    god.Step(hip);
    EXPECT_EQ(god.proxy_W_m(), hip);
    EXPECT_EQ(god.force_W_N(), Vector3d::Zero());
    EXPECT_FALSE(god.in_contact());
  }
}

TEST(GodObject, FlatPlaneProjectsTheHip) {
  const double r = 0.5e-3;
  GodObject god(Params(r));
  god.AddMesh(MakeQuad(Vector3d(-0.1, -0.1, 0), Vector3d(0.1, -0.1, 0), Vector3d(0.1, 0.1, 0),
                       Vector3d(-0.1, 0.1, 0), Vector3d::UnitZ()),
              Eigen::Isometry3d::Identity());
  god.Reset(Vector3d(0.01, 0.02, 0.01));
  // Sliding across both triangles (and their shared diagonal) at varying depth.
  for (int i = 0; i <= 100; ++i) {
    const double depth_m = 1e-3 + 2e-3 * std::sin(0.1 * i) * std::sin(0.1 * i);
    const Vector3d hip(0.01 - 2e-4 * i, 0.02 - 3e-4 * i, -depth_m);
    god.Step(hip);
    ASSERT_TRUE(god.in_contact()) << i;
    EXPECT_EQ(god.num_active_constraints(), 1);
    EXPECT_NEAR((god.proxy_W_m() - Vector3d(hip.x(), hip.y(), r + kEpsilon)).norm(), 0.0,
                kPosition_m);
    EXPECT_NEAR(
        (god.force_W_N() - kStiffness * (r + kEpsilon + depth_m) * Vector3d::UnitZ()).norm(), 0.0,
        kForce_N);
    EXPECT_NEAR(god.normal_force_N(), kStiffness * (r + kEpsilon + depth_m), kForce_N);
  }
  // Lifting the HIP above the offset plane releases the proxy.
  god.Step(Vector3d(0.0, 0.0, r + 2 * kEpsilon));
  EXPECT_FALSE(god.in_contact());
  EXPECT_EQ(god.force_W_N(), Vector3d::Zero());
}

// A 1 mm plate (a closed box) and a HIP moving straight through it at 1 m/s, 1 mm per 1 ms
// step: the proxy stays on the near face and the force grows as k × depth.
TEST(GodObject, NeverPassesAThinPlate) {
  for (const double r : {0.0, 0.3e-3}) {
    GodObject god(Params(r));
    god.AddMesh(MakeBox(Vector3d(-0.05, -0.05, -1e-3), Vector3d(0.05, 0.05, 0.0)),
                Eigen::Isometry3d::Identity());
    god.Reset(Vector3d(0.001, 0.002, 0.005));
    for (int i = 1; i <= 20; ++i) {
      const Vector3d hip(0.001, 0.002, 0.005 - 1e-3 * i);  // to 15 mm below the top face
      god.Step(hip);
      if (hip.z() > r - 1e-12) continue;  // (on the offset plane to round-off: either way)
      ASSERT_TRUE(god.in_contact()) << "r " << r << " step " << i;
      EXPECT_NEAR(god.proxy_W_m().z(), r + kEpsilon, kPosition_m);
      EXPECT_NEAR(god.force_W_N().z(), kStiffness * (r + kEpsilon - hip.z()), kForce_N);
    }
  }
}

// The inside of a box corner (floor z = 0, walls x = 0 and y = 0, all facing the octant x, y,
// z > 0): the proxy is held at the corner of the offset planes, three constraints.
TEST(GodObject, ConcaveCornerHoldsTheProxyAtTheCorner) {
  const double r = 0.5e-3, L = 0.05;
  const std::vector<Vector3d> v = {
      Vector3d::Zero(),  L * Vector3d::UnitX(), L * Vector3d::UnitY(), L * Vector3d::UnitZ(),
      Vector3d(L, L, 0), Vector3d(L, 0, L),     Vector3d(0, L, L)};
  const TriangleMesh corner = MakeMesh(
      v, {{0, 1, 4}, {0, 4, 2}, {0, 2, 6}, {0, 6, 3}, {0, 3, 5}, {0, 5, 1}}, [](const Vector3d& p) {
        int axis;
        p.minCoeff(&axis);  // the face's own coordinate is 0
        return Vector3d(Vector3d::Unit(axis));
      });
  GodObject god(Params(r));
  god.AddMesh(corner, Eigen::Isometry3d::Identity());
  god.Reset(Vector3d(5e-3, 5e-3, 5e-3));
  const Vector3d hip(-1e-3, -2e-3, -3e-3);
  god.Step(hip);
  const Vector3d expected = (r + kEpsilon) * Vector3d::Ones();
  EXPECT_NEAR((god.proxy_W_m() - expected).norm(), 0.0, kPosition_m);
  ASSERT_EQ(god.num_active_constraints(), 3);
  Vector3d normals_sum = Vector3d::Zero();
  for (int i = 0; i < 3; ++i) normals_sum += god.active_constraint(i).normal_W;
  EXPECT_NEAR((normals_sum - Vector3d::Ones()).norm(), 0.0, 1e-15);  // one of each wall
  EXPECT_NEAR((god.force_W_N() - kStiffness * (expected - hip)).norm(), 0.0, kForce_N);
  // Pressing further keeps it there.
  god.Step(hip - Vector3d(1e-3, 2e-3, 0.5e-3));
  EXPECT_NEAR((god.proxy_W_m() - expected).norm(), 0.0, kPosition_m);
}

// A concave wedge: floor z = 0 (x > 0) and a slope at 40° rising to x < 0 (normal
// (sin 40°, 0, cos 40°)). Pushed into it, the proxy is on the line where the offset planes meet:
// z = r + ε, x = (r + ε) tan 20° (the bisector of the 140° wedge), y = the HIP's.
TEST(GodObject, ConcaveWedgeHoldsTheProxyOnTheLine) {
  const double r = 0.5e-3, L = 0.05, beta = 40.0 * kPi / 180.0;
  const Vector3d up_slope(-std::cos(beta), 0.0, std::sin(beta));
  const Vector3d n_slope(std::sin(beta), 0.0, std::cos(beta));
  const Vector3d y = L * Vector3d::UnitY();
  const TriangleMesh wedge = MakeMesh(
      {-y, y, Vector3d(L, 0, 0) - y, Vector3d(L, 0, 0) + y, L * up_slope - y, L * up_slope + y},
      {{0, 2, 3}, {0, 3, 1}, {0, 4, 5}, {0, 5, 1}},
      [&](const Vector3d& p) { return p.x() > 0 ? Vector3d(Vector3d::UnitZ()) : n_slope; });
  GodObject god(Params(r));
  god.AddMesh(wedge, Eigen::Isometry3d::Identity());
  god.Reset(Vector3d(1e-3, 0.0, 5e-3));
  const Vector3d hip(0.0, 0.3e-3, -3e-3);
  god.Step(hip);
  const Vector3d expected((r + kEpsilon) * std::tan(beta / 2.0), hip.y(), r + kEpsilon);
  EXPECT_EQ(god.num_active_constraints(), 2);
  EXPECT_NEAR((god.proxy_W_m() - expected).norm(), 0.0, kPosition_m);
}

// The two steps round a convex edge (thesis fig. 3-5): a roof ridge of exterior angle 60°.
TEST(GodObject, ConvexEdgeTakesTwoSteps) {
  const double r = 1e-3, alpha = 30.0 * kPi / 180.0;
  const Vector3d n_a(-std::sin(alpha), 0.0, std::cos(alpha)),
      t_a(std::cos(alpha), 0, std::sin(alpha));
  const Vector3d n_b(std::sin(alpha), 0.0, std::cos(alpha));
  GodObject god(Params(r));
  god.AddMesh(MakeRoof(alpha, 0.05, 0.05), Eigen::Isometry3d::Identity());
  // On A's offset plane, points r n_A + u t_A: the offset planes meet at u_L = r tan α.
  const double u_l = r * std::tan(alpha);
  const double u0 = -2e-3;
  god.Reset(r * n_a + u0 * t_a + 5e-3 * n_a);
  god.Step((r - 2e-3) * n_a + u0 * t_a);
  EXPECT_NEAR((god.proxy_W_m() - ((r + kEpsilon) * n_a + u0 * t_a)).norm(), 0.0, kPosition_m);

  // The HIP moves past the ridge, 3 mm under A's plane, 1 mm beyond where the planes meet.
  const double u1 = u_l + 1e-3;
  const Vector3d hip = (r - 3e-3) * n_a + u1 * t_a;
  ASSERT_LT(n_b.dot(hip), r);  // behind B's offset plane too
  // Step 1: the proxy slides in A's plane past the edge, over B.
  god.Step(hip);
  ASSERT_EQ(god.num_active_constraints(), 1);
  EXPECT_NEAR((god.active_constraint(0).normal_W - n_a).norm(), 0.0, 1e-15);
  const Vector3d first = (r + kEpsilon) * n_a + u1 * t_a;
  EXPECT_NEAR((god.proxy_W_m() - first).norm(), 0.0, kPosition_m);
  ASSERT_GT(n_b.dot(first), r);  // in front of B: its plane is crossed next
  // Step 2, same HIP: it falls onto B, at the HIP's projection on B's offset plane.
  god.Step(hip);
  ASSERT_EQ(god.num_active_constraints(), 1);
  EXPECT_NEAR((god.active_constraint(0).normal_W - n_b).norm(), 0.0, 1e-15);
  const Vector3d second = hip + (r + kEpsilon - n_b.dot(hip)) * n_b;
  EXPECT_NEAR((god.proxy_W_m() - second).norm(), 0.0, kPosition_m);
}

// HIP pressed d = 2 mm into a plane and dragged along x by δ per step: the proxy sticks while
// |F_t| ≤ μ_s |F_n|, slips to |F_t| = μ_d |F_n|, a sawtooth between the two.
TEST(GodObject, FrictionSawtoothBetweenTheTwoCoefficients) {
  const double mu_s = 0.6, mu_d = 0.4, depth_m = 2e-3, delta_m = 5e-6;
  GodObjectParams params = Params();
  params.static_friction = mu_s;
  params.dynamic_friction = mu_d;
  GodObject god(params);
  god.AddMesh(MakeQuad(Vector3d(-0.1, -0.1, 0), Vector3d(0.1, -0.1, 0), Vector3d(0.1, 0.1, 0),
                       Vector3d(-0.1, 0.1, 0), Vector3d::UnitZ()),
              Eigen::Isometry3d::Identity());
  god.Reset(Vector3d(0, 0, 1e-3));
  god.Step(Vector3d(0, 0, -depth_m));
  ASSERT_TRUE(god.stuck());
  // The ratio grows by δ / (d + ε) a step while stuck: the peaks lie within that of μ_s.
  const double per_step = delta_m / depth_m;
  // Ratio tolerance: F_t / F_n are quotients of millimetre-sized differences, ~1e-13 relative.
  const double kRatio = 1e-9;
  int slips = 0;
  double peak = 0.0, lowest_peak = 1.0, highest_trough = 0.0, lowest_trough = 1.0;
  Vector3d last_proxy = god.proxy_W_m();
  const int steps = 2000;  // 10 mm of travel
  for (int i = 1; i <= steps; ++i) {
    god.Step(Vector3d(delta_m * i, 0, -depth_m));
    const Vector3d f = god.force_W_N();
    const double ratio = std::hypot(f.x(), f.y()) / f.z();
    EXPECT_LE(ratio, mu_s + kRatio) << i;
    if (god.stuck()) {
      EXPECT_EQ(god.proxy_W_m(), last_proxy) << i;
      peak = std::max(peak, ratio);
    } else {
      ++slips;
      EXPECT_NEAR(ratio, mu_d, kRatio) << i;           // the new stiction point's trough
      EXPECT_GE(peak, mu_s - per_step - kRatio) << i;  // the peak just before the slip
      lowest_peak = std::min(lowest_peak, peak);
      highest_trough = std::max(highest_trough, ratio);
      lowest_trough = std::min(lowest_trough, ratio);
      EXPECT_GT(god.proxy_W_m().x(), last_proxy.x());
      peak = 0.0;
    }
    last_proxy = god.proxy_W_m();
  }
  // Each stick phase lasts (μ_s − μ_d) d of HIP travel (first one: μ_s d), plus up to one step
  // δ (it ends at the first step past the threshold): 22 phases lose at most 22 δ = 0.28 of a
  // phase, hence ±1.
  const double travel_m = delta_m * steps;
  const int expected =
      1 + static_cast<int>((travel_m - mu_s * depth_m) / ((mu_s - mu_d) * depth_m));
  EXPECT_NEAR(slips, expected, 1);
  std::printf("friction: %d slips (expected %d), peaks >= %.6f, troughs %.12f..%.12f\n", slips,
              expected, lowest_peak, lowest_trough, highest_trough);
}

// A shallow roof ridge (exterior angle 2α = 20°), the HIP swept across it at a constant depth
// D below the faces. Without shading the force turns by 20° in one step (the god-object drops
// from A's plane onto B). With shading the normal is interpolated from the eave's (n_A) to the
// ridge's (the bisector) over one triangle width w; the nlerp of unit vectors φ apart turns at
// most 2 tan(φ/2) per unit of its parameter (at the midpoint), here φ = α, so the direction
// turns by at most 2 tan(α/2) Δs / w for a contact-point move Δs. Δs per step is at most the HIP
// step δ, except where the god-object drops onto B: there it moves by at most the HIP's depth
// under A's plane, s* = D (cos α + sin α tan 2α) (where A's projection passes the ridge), times
// sin 2α, plus 2δ (the overshoot step and the next). So each step turns by at most
// 2 tan(α/2) (2δ + s* sin 2α) / w.
TEST(GodObject, ShadingSpreadsTheTurnAtARidge) {
  const double alpha = 10.0 * kPi / 180.0, w = 0.01, depth_m = 1e-3, delta_m = 1e-4;
  double max_step[2] = {0.0, 0.0};
  double total[2] = {0.0, 0.0};
  for (int shading = 0; shading < 2; ++shading) {
    GodObjectParams params = Params();
    params.shading = shading == 1;
    GodObject god(params);
    god.AddMesh(MakeRoof(alpha, w, 0.05), Eigen::Isometry3d::Identity());
    const auto hip_at = [&](double x) {
      return Vector3d(x, 0.001, -std::abs(x) * std::tan(alpha) - depth_m / std::cos(alpha));
    };
    god.Reset(hip_at(-8e-3) + Vector3d(0, 0, 0.01));
    god.Step(hip_at(-8e-3));
    ASSERT_TRUE(god.in_contact());
    Vector3d last = god.force_W_N().normalized();
    for (int i = 1; i <= 160; ++i) {  // to x = +8 mm
      god.Step(hip_at(-8e-3 + delta_m * i));
      ASSERT_TRUE(god.in_contact()) << i;
      const Vector3d dir = god.force_W_N().normalized();
      max_step[shading] = std::max(max_step[shading], Angle(last, dir));
      total[shading] += Angle(last, dir);
      last = dir;
    }
  }
  const double s_star = depth_m * (std::cos(alpha) + std::sin(alpha) * std::tan(2 * alpha));
  const double bound =
      2.0 * std::tan(alpha / 2.0) * (2 * delta_m + s_star * std::sin(2 * alpha)) / w;
  // Without shading: the whole dihedral angle in one step, nothing elsewhere (1e-12 rad: the
  // normals are unit vectors computed to ~1e-16).
  EXPECT_NEAR(max_step[0], 2 * alpha, 1e-12);
  EXPECT_NEAR(total[0], 2 * alpha, 1e-12);
  EXPECT_LE(max_step[1], bound);
  EXPECT_GT(total[1], alpha);  // it does turn (from the eave normal past the bisector)
  RecordProperty("unshaded_max_deg_per_mm",
                 std::to_string(max_step[0] * 180 / kPi / (delta_m * 1e3)));
  RecordProperty("shaded_max_deg_per_mm",
                 std::to_string(max_step[1] * 180 / kPi / (delta_m * 1e3)));
  RecordProperty("shaded_bound_deg_per_mm", std::to_string(bound * 180 / kPi / (delta_m * 1e3)));
  std::printf(
      "ridge 20 deg: max turn per mm of HIP travel: unshaded %.2f deg, shaded %.3f deg "
      "(bound %.3f deg)\n",
      max_step[0] * 180 / kPi / (delta_m * 1e3), max_step[1] * 180 / kPi / (delta_m * 1e3),
      bound * 180 / kPi / (delta_m * 1e3));
}

// A plate moving up at 0.1 m/s (0.1 mm per 1 ms step) under a HIP held still: once it reaches
// the HIP it carries the proxy up on its offset plane.
TEST(GodObject, MovingPlateCarriesTheProxy) {
  const double r = 0.2e-3, speed_m_per_step = 1e-4;
  GodObject god(Params(r));
  const int id = god.AddMesh(MakeBox(Vector3d(-0.05, -0.05, -1e-3), Vector3d(0.05, 0.05, 0.0)),
                             Eigen::Isometry3d::Identity());
  const Vector3d hip(0.003, -0.002, 0.55e-3);  // between two plate positions
  god.Step(hip);
  int in_contact = 0;
  for (int i = 1; i <= 40; ++i) {
    const double plate_z = speed_m_per_step * i;
    god.SetMeshPose(id, Eigen::Isometry3d(Eigen::Translation3d(0, 0, plate_z)));
    god.Step(hip);
    if (plate_z + r <= hip.z()) {
      EXPECT_FALSE(god.in_contact()) << i;
      continue;
    }
    ++in_contact;
    ASSERT_TRUE(god.in_contact()) << i;
    EXPECT_NEAR((god.proxy_W_m() - Vector3d(hip.x(), hip.y(), plate_z + r + kEpsilon)).norm(), 0.0,
                kPosition_m);
    EXPECT_NEAR(god.force_W_N().z(), kStiffness * (plate_z + r + kEpsilon - hip.z()), kForce_N);
  }
  EXPECT_GT(in_contact, 30);
}

// The deformable body's surface snapshot: new vertices move a resting proxy with the surface
// (it keeps its place on its triangle), and the vertex normals follow. A box's corner normal is
// (±1, ±1, ±1)/√3: the three faces meet there at 90° each (split or not into triangles).
TEST(GodObject, NewVerticesCarryTheProxyAndUpdateTheNormals) {
  const double r = 0.2e-3;
  GodObject god(Params(r));
  const TriangleMesh box = MakeBox(Vector3d(-0.05, -0.05, -0.01), Vector3d(0.05, 0.05, 0.0));
  const int id = god.AddMesh(box, Eigen::Isometry3d::Identity());
  for (int v = 0; v < 8; ++v) {  // MakeBox's corner v: bit 0 x, bit 1 y, bit 2 z at the max
    const Vector3d expected =
        Vector3d(v & 1 ? 1 : -1, v & 2 ? 1 : -1, v & 4 ? 1 : -1) / std::sqrt(3.0);
    EXPECT_NEAR((god.vertex_normals_O(id).col(v) - expected).norm(), 0.0, 1e-15) << v;
  }
  const Vector3d hip(0.01, 0.02, -1e-3);
  god.Reset(Vector3d(0.01, 0.02, 0.01));
  god.Step(hip);
  ASSERT_TRUE(god.in_contact());
  // The box grows 0.5 mm upwards (top vertices raised): the proxy rides up with the top face.
  Matrix3Xd grown = box.vertices_m;
  for (int v = 4; v < 8; ++v) grown(2, v) += 0.5e-3;
  god.SetMeshVertices(id, grown);
  god.Step(hip);
  ASSERT_TRUE(god.in_contact());
  EXPECT_NEAR((god.proxy_W_m() - Vector3d(hip.x(), hip.y(), 0.5e-3 + r + kEpsilon)).norm(), 0.0,
              kPosition_m);
}

// A lattice whose centre vertex sinks by `depth_m` (a dimple: a concave cone of four or eight
// faces), 4 mm spacing, as a visual tool pressing one node of a body's surface leaves it.
TriangleMesh MakeDimple(double depth_m) {
  const int n = 10;
  const double h = 0.004;
  TriangleMesh mesh;
  mesh.vertices_m.resize(3, (n + 1) * (n + 1));
  mesh.triangles.resize(3, 2 * n * n);
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const bool centre = i == n / 2 && j == n / 2;
      mesh.vertices_m.col(j * (n + 1) + i) << (i - n / 2) * h, (j - n / 2) * h,
          centre ? -depth_m : 0.0;
    }
  }
  for (int j = 0, f = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      if ((i + j) % 2 == 0) {
        mesh.triangles.col(f++) << a, a + 1, a + n + 2;
        mesh.triangles.col(f++) << a, a + n + 2, a + n + 1;
      } else {
        mesh.triangles.col(f++) << a, a + 1, a + n + 1;
        mesh.triangles.col(f++) << a + 1, a + n + 2, a + n + 1;
      }
    }
  }
  return mesh;
}

// Distance from p to the nearest triangle of the mesh, by brute force (a second method).
double CalcMeshDistance(const TriangleMesh& mesh, const Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (int f = 0; f < mesh.triangles.cols(); ++f) {
    const Vector3d q = CalcClosestPointOnTriangle(p, mesh.vertices_m.col(mesh.triangles(0, f)),
                                                  mesh.vertices_m.col(mesh.triangles(1, f)),
                                                  mesh.vertices_m.col(mesh.triangles(2, f)))
                           .point;
    best = std::min(best, (p - q).norm());
  }
  return best;
}

TEST(GodObject, DeepeningDimpleNeverLetsTheProxyThrough) {
  // The HIP descends 10 µm per step near the centre; every 20 steps the dimple is redrawn
  // deeper, trailing the HIP (its centre at the HIP's sphere bottom, as a visual tool would
  // leave it). Carried on one face alone, the proxy ends up behind the dimple's other faces and
  // falls through (it did, before re-seating); the proxy must keep its radius from the surface.
  GodObjectParams params;
  params.stiffness_N_m = kStiffness;
  params.proxy_radius_m = 0.001;
  GodObject god(params);
  const int id = god.AddMesh(MakeDimple(0.0), Eigen::Isometry3d::Identity());
  god.Reset(Vector3d(1e-4, 5e-5, 0.005));
  TriangleMesh mesh = MakeDimple(0.0);
  int in_contact = 0;
  for (int k = 0; k < 1000; ++k) {
    const Vector3d hip(1e-4, 5e-5, 0.005 - 1e-5 * k);
    if (k % 20 == 0) {
      mesh = MakeDimple(std::max(0.0, -(hip.z() + 0.001) - 5e-4));
      god.SetMeshVertices(id, mesh.vertices_m);
    }
    god.Step(hip);
    // In contact once the HIP is within r of the rim level; never closer than r to the surface.
    if (hip.z() < 0.0) {
      ASSERT_TRUE(god.in_contact()) << k;
      ++in_contact;
    }
    ASSERT_GE(CalcMeshDistance(mesh, god.proxy_W_m()), params.proxy_radius_m - 1e-9) << k;
  }
  EXPECT_EQ(in_contact, 499);
}

// Texture: sliding along x on a plane, the normal force is k (d + ε + A sin(2π x / λ)).
TEST(GodObject, BumpTextureModulatesTheNormalForce) {
  GodObjectParams params = Params();
  params.texture_amplitude_m = 0.1e-3;
  params.texture_wavelength_m = 2e-3;
  GodObject god(params);
  god.AddMesh(MakeQuad(Vector3d(-0.1, -0.1, 0), Vector3d(0.1, -0.1, 0), Vector3d(0.1, 0.1, 0),
                       Vector3d(-0.1, 0.1, 0), Vector3d::UnitZ()),
              Eigen::Isometry3d::Identity());
  god.Reset(Vector3d(0, 0, 1e-3));
  for (int i = 0; i < 100; ++i) {
    const double x = 1e-4 * i, depth_m = 1e-3;
    god.Step(Vector3d(x, 0, -depth_m));
    const double h = 0.1e-3 * std::sin(2 * kPi * x / 2e-3);
    EXPECT_NEAR(god.force_W_N().z(), kStiffness * (depth_m + kEpsilon + h), kForce_N);
    EXPECT_NEAR(god.force_W_N().head<2>().norm(), 0.0, kForce_N);
  }
}

// The piecewise-linear height of MakeHeightField(n, size_m, ·) at (x, y).
double HeightFieldZ(const TriangleMesh& field, int n, double size_m, double x, double y) {
  const double u = (x / size_m + 0.5) * n, v = (y / size_m + 0.5) * n;
  const int i = static_cast<int>(std::floor(u)), j = static_cast<int>(std::floor(v));
  const double fx = u - i, fy = v - j;
  const int a = j * (n + 1) + i;
  const auto z = [&](int k) { return field.vertices_m(2, k); };
  if (fx >= fy) return z(a) + fx * (z(a + 1) - z(a)) + fy * (z(a + n + 2) - z(a + 1));
  return z(a) + fy * (z(a + n + 1) - z(a)) + fx * (z(a + n + 2) - z(a + n + 1));
}

// Sliding round a circle over a finely tessellated bumpy surface (100k triangles, saddles
// everywhere, neighbouring normals a fraction of a degree apart): the god-object never goes
// below the surface and stays in contact while the HIP is under it. (Nearly dependent planes
// once let the search stop with the goal behind a third plane.)
TEST(GodObject, NeverFallsThroughAFineBumpySurface) {
  const int n = 224;
  const double size_m = 0.2;
  const TriangleMesh field = MakeHeightField(
      n, size_m, [](double x, double y) { return 3e-3 * std::sin(60 * x) * std::sin(60 * y); });
  for (const double r : {0.0, 0.5e-3}) {
    GodObject god(Params(r));
    god.AddMesh(field, Eigen::Isometry3d::Identity());
    god.Reset(Vector3d(0.05, 0.0, 0.02));
    for (int i = 0; i < 4000; ++i) {
      const double a = 0.02 * i;  // 1 mm steps round a 5 cm circle, 2 mm below z = 0
      const Vector3d hip(0.05 * std::cos(a), 0.05 * std::sin(a), -2e-3);
      god.Step(hip);
      const Vector3d& g = god.god_object_W_m();
      // Below the surface under it by no more than round-off (1e-12 m, far below ε).
      ASSERT_GE(g.z() - HeightFieldZ(field, n, size_m, g.x(), g.y()), -1e-12) << r << " " << i;
      if (hip.z() < HeightFieldZ(field, n, size_m, hip.x(), hip.y())) {
        ASSERT_TRUE(god.in_contact()) << r << " " << i;
      }
    }
  }
}

TEST(GodObject, StepAllocatesNothing) {
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations are not counted here";
  GodObjectParams params = Params(0.5e-3);
  params.static_friction = 0.5;
  params.dynamic_friction = 0.3;
  params.shading = true;
  params.texture_amplitude_m = 1e-5;
  GodObject god(params);
  const auto bumps = [](double x, double y) { return 2e-3 * std::sin(60 * x) * std::sin(60 * y); };
  const TriangleMesh field = MakeHeightField(71, 0.2, bumps);  // 10,082 triangles
  ASSERT_GT(field.triangles.cols(), 10000);
  const int id = god.AddMesh(field, Eigen::Isometry3d::Identity());
  const auto hip_at = [&](int i) {
    const double a = 0.01 * i;
    return Vector3d(0.05 * std::cos(a), 0.05 * std::sin(a), -3e-3);
  };
  god.Reset(Vector3d(0.05, 0, 0.01));
  for (int i = 0; i < 10; ++i) god.Step(hip_at(i));
  Matrix3Xd moved = field.vertices_m;
  moved.row(2).array() += 1e-4;
  god.SetMeshVertices(id, moved);
  AllocationCounter counter;
  int contacts = 0;
  for (int i = 10; i < 1010; ++i) {
    god.SetMeshPose(id, Eigen::Isometry3d(Eigen::Translation3d(0, 0, 1e-6 * (i % 7))));
    god.Step(hip_at(i));
    contacts += god.in_contact();
  }
  god.SetMeshVertices(id, field.vertices_m);
  EXPECT_EQ(counter.count(), 0);
  EXPECT_GT(contacts, 900);
}

// The tree's query against testing every triangle, on random segments through a bumpy field
// and a box (offset and widened by r): the same first crossing.
TEST(GodObject, TreeFindsTheFirstCrossingOfBruteForce) {
  GodObject god(Params(0.5e-3));
  const auto bumps = [](double x, double y) { return 5e-3 * std::sin(80 * x) * std::cos(50 * y); };
  const int field = god.AddMesh(MakeHeightField(40, 0.1, bumps), Eigen::Isometry3d::Identity());
  const int box = god.AddMesh(MakeBox(Vector3d(-0.02, -0.03, -0.01), Vector3d(0.03, 0.02, 0.0)),
                              Eigen::Isometry3d::Identity());
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.06, 0.06);
  int hits = 0;
  const int trials = 4000;
  for (int i = 0; i < trials; ++i) {
    const int id = i % 2 == 0 ? field : box;
    const Vector3d p0(u(rng), u(rng), 0.2 * u(rng)), p1(u(rng), u(rng), 0.2 * u(rng));
    const GodObject::Crossing tree = god.CalcFirstCrossing(id, p0, p1);
    const GodObject::Crossing brute = god.CalcFirstCrossingBruteForce(id, p0, p1);
    ASSERT_EQ(tree.triangle, brute.triangle) << i;
    EXPECT_EQ(tree.t, brute.t) << i;
    hits += brute.triangle >= 0;
  }
  EXPECT_GT(hits, trials / 10);  // not vacuous
}

}  // namespace
}  // namespace hapsim::contact
