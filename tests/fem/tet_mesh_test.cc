// Lattice mesher and mesh utilities against closed-form geometry: counts, volumes (sum of tet
// volumes vs the box, divergence theorem over the extracted surface), conformity (every interior
// face shared by exactly two tets), and the ellipsoid volume 4/3 π abc.
#include "fem/tet_mesh.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "fem/lattice_mesher.h"

namespace hapsim::fem {
namespace {

double SumOfVolumes(const TetMesh& mesh) {
  double volume_m3 = 0.0;
  for (int t = 0; t < mesh.num_tets(); ++t)
    volume_m3 += CalcSignedVolume(mesh.rest_positions_m, mesh.tets.col(t));
  return volume_m3;
}

// Divergence theorem with the field p/3 (div = 1): V = Σ_faces (p_centroid · n) A / 3.
double VolumeFromSurface(const TetMesh& mesh, const Matrix3Xi& surface) {
  double volume_m3 = 0.0;
  for (Eigen::Index f = 0; f < surface.cols(); ++f) {
    const Eigen::Vector3d a = mesh.rest_positions_m.col(surface(0, f));
    const Eigen::Vector3d b = mesh.rest_positions_m.col(surface(1, f));
    const Eigen::Vector3d c = mesh.rest_positions_m.col(surface(2, f));
    const Eigen::Vector3d area_normal = 0.5 * (b - a).cross(c - a);  // |.| = area, outward
    volume_m3 += ((a + b + c) / 3.0).dot(area_normal) / 3.0;
  }
  return volume_m3;
}

TEST(LatticeMesher, ReferenceBlockHasDesignCounts) {
  const TetMesh mesh = MakeBoxTetMesh({-0.05, -0.05, 0.0}, {0.05, 0.05, 0.05}, {12, 12, 5});
  EXPECT_EQ(mesh.num_nodes(), 1014);  // DESIGN.md §7
  EXPECT_EQ(mesh.num_tets(), 3600);
  EXPECT_FALSE(FindRestMeshProblem(mesh).has_value());
}

TEST(LatticeMesher, VolumesAndSurfaceMatchTheBox) {
  const TetMesh mesh = MakeBoxTetMesh({0.0, 0.0, 0.0}, {0.3, 0.2, 0.1}, {3, 4, 2});
  const double box_volume_m3 = 0.3 * 0.2 * 0.1;
  EXPECT_NEAR(SumOfVolumes(mesh), box_volume_m3, 1e-15);
  for (int t = 0; t < mesh.num_tets(); ++t)
    EXPECT_GT(CalcTetQuality(mesh.rest_positions_m, mesh.tets.col(t)), 0.5);
  const Matrix3Xi surface = ExtractBoundarySurface(mesh);
  // Each boundary cell face is cut into two triangles: 2·(3·4 + 4·2 + 3·2)·2 faces.
  EXPECT_EQ(surface.cols(), 2 * 2 * (3 * 4 + 4 * 2 + 3 * 2));
  // Outward orientation: the divergence theorem gives +V (inward faces would give −V).
  EXPECT_NEAR(VolumeFromSurface(mesh, surface), box_volume_m3, 1e-15);
}

// The graded axis against its defining law h(x) = h0 (1 + (r − 1)|x − f| / D): the cell next to
// the focus and the cell at the farther end differ by the ratio (to within the change of h over
// one cell), sizes grow monotonically away from the focus, and the ends are exact.
TEST(LatticeMesher, GradedAxisFollowsItsSizeLaw) {
  const double ratio = 6.0;
  const Eigen::VectorXd x = MakeGradedAxis(-0.03, 0.03, 40, 0.0, ratio);
  ASSERT_EQ(x.size(), 41);
  EXPECT_EQ(x[0], -0.03);
  EXPECT_EQ(x[40], 0.03);
  const Eigen::VectorXd h = x.tail(40) - x.head(40);
  for (int i = 0; i < 20; ++i) {
    EXPECT_NEAR(h[19 - i], h[20 + i], 1e-15);  // symmetric about the centred focus
    if (i > 0) {
      EXPECT_GT(h[20 + i], h[19 + i]);
    }
  }
  // At cell midpoints h / (1 + (r − 1)|x_mid| / D) is the same h0 everywhere, to O(h²).
  auto h0_at = [&](int i) {
    return h[i] / (1.0 + (ratio - 1.0) * std::abs(0.5 * (x[i] + x[i + 1])) / 0.03);
  };
  for (int i = 0; i < 40; ++i) EXPECT_NEAR(h0_at(i), h0_at(20), 0.01 * h0_at(20));
  EXPECT_NEAR(h[39] / h[20], ratio, 0.1 * ratio);
  // Ratio 1 is the uniform lattice; a focus at one end grades one way only.
  const Eigen::VectorXd uniform = MakeGradedAxis(0.0, 0.1, 4, 0.05, 1.0);
  for (int i = 0; i <= 4; ++i) EXPECT_NEAR(uniform[i], 0.025 * i, 1e-15);
  const Eigen::VectorXd one_way = MakeGradedAxis(0.0, 0.03, 10, 0.03, 4.0);
  auto law = [](double mid_m) { return 1.0 + 3.0 * std::abs(mid_m - 0.03) / 0.03; };
  const double expected =
      law(0.5 * (one_way[0] + one_way[1])) / law(0.5 * (one_way[9] + one_way[10]));
  EXPECT_NEAR((one_way[1] - one_way[0]) / (one_way[10] - one_way[9]), expected, 0.02 * expected);
  EXPECT_THROW(MakeGradedAxis(0.0, 0.1, 4, 0.2, 2.0), std::invalid_argument);
  EXPECT_THROW(MakeGradedAxis(0.0, 0.1, 4, 0.05, 0.5), std::invalid_argument);
}

TEST(LatticeMesher, GradedBoxIsAConformingBox) {
  const TetMesh mesh =
      MakeGradedBoxTetMesh({-0.03, -0.03, 0.0}, {0.03, 0.03, 0.03}, {8, 8, 6}, {0, 0, 0.03}, 5.0);
  EXPECT_EQ(mesh.num_nodes(), 9 * 9 * 7);
  EXPECT_EQ(mesh.num_tets(), 5 * 8 * 8 * 6);
  EXPECT_FALSE(FindRestMeshProblem(mesh).has_value());
  const double box_volume_m3 = 0.06 * 0.06 * 0.03;
  EXPECT_NEAR(SumOfVolumes(mesh), box_volume_m3, 1e-15);
  EXPECT_NEAR(VolumeFromSurface(mesh, ExtractBoundarySurface(mesh)), box_volume_m3, 1e-15);
}

// The O-grid bend for a punch of radius R = 3 mm over the 16 × 16 × 8 lattice graded 10 times: the
// ring of nodes whose axis coordinate is nearest R (ring k, found here from the axis) lies on the
// circle, 8k nodes in each of the 9 layers; ring 1 inside it on the circle R s₁/s_k; the fade's
// ring between where the bend and the straight lattice would put it; every node keeps its height
// and its direction from the focus; nodes from ring 2k outwards keep their places; no tet folds or
// flattens.
TEST(LatticeMesher, CircleBendPutsARingOfNodesOnTheCircle) {
  const Eigen::Vector3d min_m(-0.03, -0.03, 0.0), max_m(0.03, 0.03, 0.03), focus_m(0, 0, 0.03);
  const Eigen::Vector3i cells(16, 16, 8);
  constexpr double kRadius_m = 0.003;
  const TetMesh straight = MakeGradedBoxTetMesh(min_m, max_m, cells, focus_m, 10.0);
  const TetMesh bent = MakeGradedBoxTetMesh(min_m, max_m, cells, focus_m, 10.0, kRadius_m);
  const Eigen::VectorXd axis = MakeGradedAxis(-0.03, 0.03, 16, 0.0, 10.0);
  const auto s = [&](int ring) { return axis[8 + ring]; };  // axis[8] is the focus
  int k = 1;
  for (int m = 2; m <= 8; ++m)
    if (std::abs(s(m) - kRadius_m) < std::abs(s(k) - kRadius_m)) k = m;
  ASSERT_EQ(k, 2);  // the ring at 2.59 mm
  int on_circle = 0, on_inner_circle = 0, in_fade = 0;
  for (int n = 0; n < bent.num_nodes(); ++n) {
    const Eigen::Vector3d p = bent.rest_positions_m.col(n);
    const Eigen::Vector3d q = straight.rest_positions_m.col(n);
    EXPECT_EQ(p.z(), q.z());
    const double radius_m = std::hypot(p.x(), p.y()), straight_radius_m = std::hypot(q.x(), q.y());
    if (straight_radius_m > 0.0) {  // the same direction from the focus's vertical
      EXPECT_NEAR(p.x() * q.y() - p.y() * q.x(), 0.0, 1e-18);
      EXPECT_GT(p.x() * q.x() + p.y() * q.y(), 0.0);
    }
    const double chebyshev_m = std::max(std::abs(q.x()), std::abs(q.y()));
    if (std::abs(chebyshev_m - s(k)) < 1e-12) {
      EXPECT_NEAR(radius_m, kRadius_m, 1e-15);
      ++on_circle;
    } else if (std::abs(chebyshev_m - s(1)) < 1e-12) {
      EXPECT_NEAR(radius_m, kRadius_m * s(1) / s(k), 1e-15);
      ++on_inner_circle;
    } else if (std::abs(chebyshev_m - s(3)) < 1e-12) {
      const double bent_limit_m = kRadius_m * s(3) / s(k);
      EXPECT_GE(radius_m, std::min(bent_limit_m, straight_radius_m) - 1e-15);
      EXPECT_LE(radius_m, std::max(bent_limit_m, straight_radius_m) + 1e-15);
      ++in_fade;
    } else if (chebyshev_m >= s(2 * k) - 1e-12 || chebyshev_m == 0.0) {
      EXPECT_EQ(p, q);
    }
  }
  EXPECT_EQ(on_circle, 8 * k * (cells.z() + 1));
  EXPECT_EQ(on_inner_circle, 8 * (cells.z() + 1));
  EXPECT_EQ(in_fade, 24 * (cells.z() + 1));
  EXPECT_FALSE(FindRestMeshProblem(bent).has_value());
  double min_quality = 1.0;
  for (int t = 0; t < bent.num_tets(); ++t)
    min_quality = std::min(min_quality, CalcTetQuality(bent.rest_positions_m, bent.tets.col(t)));
  // Not a sliver (near 0). The graded lattice's own worst tet is 0.067 (cells ten times longer
  // than wide); the bend squeezes the tall cells deep under the focus to 0.026.
  EXPECT_GT(min_quality, 0.02);
  // Rings not alike in x and y (another cell count, or a box narrower in y), no node at the focus,
  // or too few rings for the fade: refused.
  EXPECT_THROW(MakeGradedBoxTetMesh(min_m, max_m, {16, 12, 8}, focus_m, 10.0, kRadius_m),
               std::invalid_argument);
  EXPECT_THROW(MakeGradedBoxTetMesh(min_m, {0.03, 0.02, 0.03}, cells, {0, -0.005, 0.03}, 10.0,
                                    kRadius_m),
               std::invalid_argument);
  EXPECT_THROW(MakeGradedBoxTetMesh(min_m, max_m, {15, 15, 8}, focus_m, 10.0, kRadius_m),
               std::invalid_argument);
  EXPECT_THROW(MakeGradedBoxTetMesh(min_m, max_m, cells, {0.001, 0, 0.03}, 10.0, kRadius_m),
               std::invalid_argument);
  EXPECT_THROW(MakeGradedBoxTetMesh(min_m, max_m, cells, focus_m, 10.0, 0.02),
               std::invalid_argument);
}

TEST(LatticeMesher, EllipsoidVolumeConvergesToAnalytic) {
  const Eigen::Vector3d radii_m(0.06, 0.04, 0.03);
  const double exact_m3 = 4.0 / 3.0 * M_PI * radii_m.prod();
  std::vector<double> errors;
  for (double cell_m : {0.012, 0.006, 0.003}) {
    const TetMesh mesh =
        MakeImplicitTetMesh(MakeEllipsoidFunction(Eigen::Vector3d::Zero(), radii_m), -radii_m * 1.1,
                            radii_m * 1.1, cell_m);
    ASSERT_FALSE(FindRestMeshProblem(mesh).has_value());
    const double error = std::abs(SumOfVolumes(mesh) - exact_m3) / exact_m3;
    EXPECT_NEAR(VolumeFromSurface(mesh, ExtractBoundarySurface(mesh)), SumOfVolumes(mesh), 1e-12);
    errors.push_back(error);
  }
  // Snapped boundary nodes make the error O(h²) where they move; the nodes left on the staircase
  // make it oscillate in sign, so convergence is asserted over a factor 4 in h, not step by step.
  EXPECT_LT(errors.back(), 0.5 * errors.front());
  EXPECT_LT(errors.back(), 0.005);
}

// Dihedral angles against closed forms: the five-tet cut of a cube is a regular tet (every angle
// arccos(1/3) = 70.53°) and four corner tets (90° at the three edges of the right corner,
// arccos(1/√3) = 54.74° at the other three); their volumes add up to the cube's.
TEST(TetMesh, QualityOfACubesFiveTets) {
  const TetMeshQuality cube = CalcTetMeshQuality(MakeBoxTetMesh({0, 0, 0}, {2, 2, 2}, {1, 1, 1}));
  EXPECT_EQ(cube.num_tets, 5);
  EXPECT_NEAR(cube.volume_m3, 8.0, 1e-14);
  EXPECT_NEAR(cube.min_dihedral_deg, std::acos(1.0 / std::sqrt(3.0)) * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(cube.max_dihedral_deg, 90.0, 1e-9);
  TetMesh regular;
  regular.rest_positions_m.resize(3, 4);
  regular.rest_positions_m << 1, 1, -1, -1, 1, -1, 1, -1, 1, -1, -1, 1;
  regular.tets.resize(4, 1);
  regular.tets << 0, 1, 2, 3;
  if (CalcSignedVolume(regular.rest_positions_m, regular.tets.col(0)) < 0.0)
    std::swap(regular.tets(2, 0), regular.tets(3, 0));
  const TetMeshQuality q = CalcTetMeshQuality(regular);
  EXPECT_NEAR(q.min_dihedral_deg, std::acos(1.0 / 3.0) * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(q.max_dihedral_deg, std::acos(1.0 / 3.0) * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(q.volume_m3, 8.0 / 3.0, 1e-14);  // edge 2√2: V = a³/(6√2)
}

TEST(TetMesh, DetectsBadRestMeshes) {
  TetMesh mesh = MakeBoxTetMesh({0, 0, 0}, {1, 1, 1}, {1, 1, 1});
  int bad = -1;
  TetMesh inverted = mesh;
  std::swap(inverted.tets(0, 2), inverted.tets(1, 2));
  EXPECT_TRUE(FindRestMeshProblem(inverted, &bad).has_value());
  EXPECT_EQ(bad, 2);
  TetMesh out_of_range = mesh;
  out_of_range.tets(3, 4) = 99;
  EXPECT_TRUE(FindRestMeshProblem(out_of_range, &bad).has_value());
  EXPECT_EQ(bad, 4);
  TetMesh flat = mesh;
  flat.rest_positions_m.col(flat.tets(3, 0)) = flat.rest_positions_m.col(flat.tets(0, 0));
  EXPECT_TRUE(FindRestMeshProblem(flat, &bad).has_value());
}

}  // namespace
}  // namespace hapsim::fem
