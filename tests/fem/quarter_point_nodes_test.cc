// fem/quarter_point_nodes.h. On the unit tet (corners at the origin and the unit axes) with the
// origin singular, the quarter-point map is x(ξ) = s ξ, s = ξ1 + ξ2 + ξ3 (worked from
// x = Σ N_a X_a with the nodes at e_i, e_i/4 and (e_i + e_j)/2: component i is
// L_i (2 L_i − 1) + L0 L_i + 2 L_i (s − L_i) = s L_i), so x1 + x2 + x3 = s² and the field
// u = (x1 + x2 + x3)^½ = s is linear in ξ: the element holds it exactly, where the straight one
// (edge nodes at the midpoints) cannot. With the origin and (1,0,0) singular (an edge on the
// singular line) the same working gives x2 + x3 = (ξ2 + ξ3)², so (x2 + x3)^½, a root of a
// distance from that edge (zero on it, linear away from it), is held as exactly.
#include "fem/quarter_point_nodes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "fem/quadratic_tet.h"
#include "tests/fem/test_utilities.h"

namespace hapsim::fem {
namespace {

using test::MakeUnitQuadraticTet;

P2Nodes NodesOf(const TetMesh& mesh, int t) {
  P2Nodes X;
  for (int a = 0; a < kP2Nodes; ++a) X.col(a) = mesh.rest_positions_m.col(mesh.node(a, t));
  return X;
}

// The largest |u_h − ρ(x)^½| over a grid of points inside the tet, u_h the quadratic interpolant
// of that field from its nodal values; ρ(x) = x1 + x2 + x3 by default.
double MaxRootFieldError(const P2Nodes& X,
                         double (*rho)(const Eigen::Vector3d&) = [](const Eigen::Vector3d& x) {
                           return x.sum();
                         }) {
  Eigen::Matrix<double, kP2Nodes, 1> u;
  for (int a = 0; a < kP2Nodes; ++a) u[a] = std::sqrt(rho(X.col(a)));
  double worst = 0.0;
  const int n = 8;
  for (int i = 1; i < n; ++i)
    for (int j = 1; i + j < n; ++j)
      for (int k = 1; i + j + k < n; ++k) {
        const Eigen::Vector3d xi(double(i) / n, double(j) / n, double(k) / n);
        const auto N = CalcP2ShapeFunctions(xi);
        const Eigen::Vector3d x = X * N;
        worst = std::max(worst, std::abs(N.dot(u) - std::sqrt(rho(x))));
      }
  return worst;
}

TEST(QuarterPointNodes, TheRootOfTheDistanceIsHeldExactlyAtAQuarter) {
  TetMesh mesh = MakeUnitQuadraticTet();
  EXPECT_GT(MaxRootFieldError(NodesOf(mesh, 0)), 1e-2);  // straight: the field is not held
  const std::vector<bool> singular = {true, false, false, false, false,
                                      false, false, false, false, false};
  EXPECT_EQ(MoveEdgeNodesToQuarterPoints(singular, 0.25, &mesh), 3);
  EXPECT_LT(MaxRootFieldError(NodesOf(mesh, 0)), 1e-14);
  // The edges leaving the origin have their nodes at a quarter; the far face's at midpoints.
  for (int k = 0; k < 6; ++k) {
    const int i = kP2EdgeCorners[k][0], j = kP2EdgeCorners[k][1];
    const Eigen::Vector3d Xi = mesh.rest_positions_m.col(i), Xj = mesh.rest_positions_m.col(j);
    const Eigen::Vector3d expected = ((i == 0 || j == 0) ? 0.25 : 0.5) * (Xi + Xj);
    EXPECT_LT((mesh.rest_positions_m.col(mesh.edge_nodes(k, 0)) - expected).norm(), 1e-15) << k;
  }
}

TEST(QuarterPointNodes, AlongASingularEdgeTheRootOfItsDistanceIsHeld) {
  const auto rho = [](const Eigen::Vector3d& x) { return x.y() + x.z(); };
  TetMesh mesh = MakeUnitQuadraticTet();
  EXPECT_GT(MaxRootFieldError(NodesOf(mesh, 0), rho), 1e-2);
  const std::vector<bool> singular = {true, true, false, false, false,
                                      false, false, false, false, false};
  EXPECT_EQ(MoveEdgeNodesToQuarterPoints(singular, 0.25, &mesh), 4);  // (0,1) itself stays
  EXPECT_LT(MaxRootFieldError(NodesOf(mesh, 0), rho), 1e-14);
}

// Exactly at a quarter the map is singular at the corner (∂x/∂ξ = 0 along each moved edge), and
// the element check refuses it; just above, it is a valid element.
TEST(QuarterPointNodes, JustAboveAQuarterTheElementIsValid) {
  const std::vector<bool> singular = {true, false, false, false, false,
                                      false, false, false, false, false};
  TetMesh at_quarter = MakeUnitQuadraticTet(), above = MakeUnitQuadraticTet();
  MoveEdgeNodesToQuarterPoints(singular, 0.25, &at_quarter);
  MoveEdgeNodesToQuarterPoints(singular, 0.26, &above);
  EXPECT_TRUE(FindQuadraticTetProblem(NodesOf(at_quarter, 0)).has_value());
  EXPECT_FALSE(FindQuadraticTetProblem(NodesOf(above, 0)).has_value());
  EXPECT_LT(MaxRootFieldError(NodesOf(above, 0)), 0.01);  // 0.003 there; 0.043 straight
}

// Two tets on the face (1, 2, 3), apexes 0 and 4, node 1 singular: its edges to 0, 2, 3 and 4
// move, once each, though (1,2) and (1,3) belong to both tets; (2,3) and the rest stay.
TEST(QuarterPointNodes, ASharedEdgeMovesOnce) {
  TetMesh linear;
  linear.rest_positions_m.resize(3, 5);
  linear.rest_positions_m << 0, 1, 0, 0, 1,  //
      0, 0, 1, 0, 1,                         //
      0, 0, 0, 1, 1;
  linear.tets.resize(4, 2);
  linear.tets << 0, 4,  //
      1, 1,             //
      2, 3,             //
      3, 2;
  ASSERT_FALSE(FindRestMeshProblem(linear).has_value());
  TetMesh mesh = MakeQuadraticMesh(linear);
  std::vector<bool> singular(static_cast<size_t>(mesh.num_nodes()), false);
  singular[1] = true;
  EXPECT_EQ(MoveEdgeNodesToQuarterPoints(singular, 0.3, &mesh), 4);
  for (int t = 0; t < 2; ++t)
    for (int k = 0; k < 6; ++k) {
      const int i = mesh.tets(kP2EdgeCorners[k][0], t), j = mesh.tets(kP2EdgeCorners[k][1], t);
      const Eigen::Vector3d Xi = mesh.rest_positions_m.col(i), Xj = mesh.rest_positions_m.col(j);
      Eigen::Vector3d expected = 0.5 * (Xi + Xj);
      if (i == 1) expected = Xi + 0.3 * (Xj - Xi);
      if (j == 1) expected = Xj + 0.3 * (Xi - Xj);
      EXPECT_LT((mesh.rest_positions_m.col(mesh.edge_nodes(k, t)) - expected).norm(), 1e-15);
    }
}

TEST(QuarterPointNodes, RefusesWhatItCannotDo) {
  TetMesh mesh = MakeUnitQuadraticTet();
  const std::vector<bool> singular(static_cast<size_t>(mesh.num_nodes()), false);
  EXPECT_THROW(MoveEdgeNodesToQuarterPoints(singular, 0.2, &mesh), std::invalid_argument);
  EXPECT_THROW(MoveEdgeNodesToQuarterPoints(singular, 0.6, &mesh), std::invalid_argument);
  EXPECT_THROW(MoveEdgeNodesToQuarterPoints({true}, 0.25, &mesh), std::invalid_argument);
  TetMesh linear;
  linear.rest_positions_m = Matrix3Xd::Identity(3, 4);
  linear.tets = Matrix4Xi::Zero(4, 1);
  EXPECT_THROW(MoveEdgeNodesToQuarterPoints({false, false, false, false}, 0.25, &linear),
               std::invalid_argument);
}

}  // namespace
}  // namespace hapsim::fem
