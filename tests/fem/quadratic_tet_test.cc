// The 10-node tetrahedron (fem/quadratic_tet.h) against independent values: closed-form
// integrals of barycentric monomials, the Kronecker property and finite differences of the shape
// functions, exact interpolation of quadratic fields, the nodal forces of a uniform stress in
// closed form, patch tests on an assembled mesh (a linear field, and a quadratic field with its
// body force), finite differences of the energy, the mass in closed form, and a rigid motion.
#include "fem/quadratic_tet.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <map>
#include <random>
#include <vector>

namespace hapsim::fem {
namespace {

double Factorial(int n) { return n <= 1 ? 1.0 : n * Factorial(n - 1); }

// The reference positions of the ten nodes.
std::array<Eigen::Vector3d, kP2Nodes> ReferenceNodes() {
  std::array<Eigen::Vector3d, kP2Nodes> xi;
  xi[0] = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) xi[k + 1] = Eigen::Vector3d::Unit(k);
  for (int k = 0; k < 6; ++k)
    xi[4 + k] = 0.5 * (xi[kP2EdgeCorners[k][0]] + xi[kP2EdgeCorners[k][1]]);
  return xi;
}

Eigen::Matrix<double, 3, 4> RandomCorners(std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(-0.2, 0.2);
  Eigen::Matrix<double, 3, 4> X;
  X << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  X *= 0.01;  // a 1 cm tet, perturbed by up to 20 % of its edge
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 3; ++r) X(r, c) += 0.01 * unit(*rng);
  return X;
}

TEST(P2Quadrature, IntegratesEveryMonomialUpToDegreeFiveExactly) {
  // ∫ L0^p L1^q L2^r L3^s over the reference tet = p! q! r! s! / (p + q + r + s + 3)!.
  int checked = 0;
  double weights = 0.0;
  for (const QuadraturePoint& point : P2Quadrature()) {
    EXPECT_GT(point.weight, 0.0);
    weights += point.weight;
  }
  EXPECT_NEAR(weights, 1.0 / 6.0, 1e-15);
  for (int p = 0; p <= 5; ++p)
    for (int q = 0; p + q <= 5; ++q)
      for (int r = 0; p + q + r <= 5; ++r)
        for (int s = 0; p + q + r + s <= 5; ++s) {
          double sum = 0.0;
          for (const QuadraturePoint& point : P2Quadrature()) {
            const double L0 = 1.0 - point.xi.sum();
            sum += point.weight * std::pow(L0, p) * std::pow(point.xi[0], q) *
                   std::pow(point.xi[1], r) * std::pow(point.xi[2], s);
          }
          const double exact = Factorial(p) * Factorial(q) * Factorial(r) * Factorial(s) /
                               Factorial(p + q + r + s + 3);
          EXPECT_NEAR(sum, exact, 1e-15 + 1e-13 * exact) << p << q << r << s;
          ++checked;
        }
  EXPECT_EQ(checked, 126);  // the monomials of degree ≤ 5 in four variables
}

TEST(P2ShapeFunctions, AreOneAtTheirNodeZeroAtTheOthersAndDifferentiateRight) {
  const auto nodes = ReferenceNodes();
  for (int b = 0; b < kP2Nodes; ++b) {
    const auto N = CalcP2ShapeFunctions(nodes[b]);
    for (int a = 0; a < kP2Nodes; ++a) EXPECT_NEAR(N[a], a == b ? 1.0 : 0.0, 1e-15);
  }
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 0.3);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Vector3d xi(unit(rng), unit(rng), unit(rng));
    EXPECT_NEAR(CalcP2ShapeFunctions(xi).sum(), 1.0, 1e-15);
    const auto dN = CalcP2ShapeDerivatives(xi);
    constexpr double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
      const Eigen::Matrix<double, kP2Nodes, 1> fd =
          (CalcP2ShapeFunctions(xi + e) - CalcP2ShapeFunctions(xi - e)) / (2 * h);
      EXPECT_LT((fd - dN.col(k)).cwiseAbs().maxCoeff(), 1e-9);
    }
  }
}

// A quadratic field f(x) = c + gᵀx + xᵀHx, its value at the nodes interpolated, against f and ∇f
// at random points of a straight element: P2 holds quadratics exactly.
TEST(P2ShapeFunctions, InterpolateAQuadraticFieldAndItsGradientExactly) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const P2Nodes X = MakeStraightP2Nodes(RandomCorners(&rng));
  const double c = unit(rng);
  const Eigen::Vector3d g(unit(rng), unit(rng), unit(rng));
  Eigen::Matrix3d H = Eigen::Matrix3d::Random();
  H = (H + H.transpose()).eval() * 100.0;
  const auto f = [&](const Eigen::Vector3d& x) { return c + g.dot(x) + x.dot(H * x); };
  Eigen::Matrix<double, kP2Nodes, 1> nodal;
  for (int a = 0; a < kP2Nodes; ++a) nodal[a] = f(X.col(a));
  std::uniform_real_distribution<double> inside(0.0, 0.3);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Vector3d xi(inside(rng), inside(rng), inside(rng));
    const Eigen::Vector3d x = X * CalcP2ShapeFunctions(xi);
    EXPECT_NEAR(CalcP2ShapeFunctions(xi).dot(nodal), f(x), 1e-13);
    const auto dN = CalcP2ShapeDerivatives(xi);
    const Eigen::Matrix3d J = X * dN;
    const Eigen::Vector3d gradient = J.transpose().inverse() * (dN.transpose() * nodal);
    EXPECT_LT((gradient - (g + 2.0 * H * x)).norm(), 1e-9 * (g.norm() + 2.0 * H.norm() * 0.02));
  }
}

constexpr double kMu = 3e4, kLambda = 2e5, kRho = 1000.0;

// σ of a uniform displacement gradient A (linear elasticity).
Eigen::Matrix3d Stress(const Eigen::Matrix3d& A) {
  return kMu * (A + A.transpose()) + kLambda * A.trace() * Eigen::Matrix3d::Identity();
}

// Under u = A X the element's nodal forces are ∫ σ ∂N_a/∂X dV with σ uniform: 0 at a corner
// (∫ (4 L_i − 1) dV = 0) and V σ (b_i + b_j) at the node of edge (i, j) (∫ 4 L_j dV = V).
TEST(QuadraticTetRest, AUniformStrainGivesTheClosedFormNodalForces) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Matrix<double, 3, 4> corners = RandomCorners(&rng);
    const P2Nodes X = MakeStraightP2Nodes(corners);
    const QuadraticTetRest rest = MakeQuadraticTetRest(X, kMu, kLambda, kRho);
    const Eigen::Matrix3d A = 1e-3 * Eigen::Matrix3d::Random();
    const P2Nodes u = A * X;
    const P2Vector f = rest.stiffness * Eigen::Map<const P2Vector>(u.data());
    const Eigen::Matrix3d sigma = Stress(A);
    const Eigen::Matrix<double, 3, 4>& b = rest.corner_gradients_1_m;
    const double V = rest.volume_m3;
    const double scale = V * sigma.norm() * b.norm();
    for (int i = 0; i < 4; ++i) EXPECT_LT(f.segment<3>(3 * i).norm(), 1e-12 * scale);
    for (int k = 0; k < 6; ++k) {
      const Eigen::Vector3d expected =
          V * sigma * (b.col(kP2EdgeCorners[k][0]) + b.col(kP2EdgeCorners[k][1]));
      EXPECT_LT((f.segment<3>(3 * (4 + k)) - expected).norm(), 1e-12 * scale) << "edge " << k;
    }
    // The volume of a straight element is its corner tet's.
    Eigen::Matrix3d D;
    for (int k = 0; k < 3; ++k) D.col(k) = corners.col(k + 1) - corners.col(0);
    EXPECT_NEAR(V, D.determinant() / 6.0, 1e-15);
  }
}

TEST(QuadraticTetRest, StiffnessHasSixRigidModesAndIsPositiveOtherwise) {
  std::mt19937 rng(9);
  const P2Nodes X = MakeStraightP2Nodes(RandomCorners(&rng));
  const QuadraticTetRest rest = MakeQuadraticTetRest(X, kMu, kLambda, kRho);
  EXPECT_LT((rest.stiffness - rest.stiffness.transpose()).norm(), 1e-12 * rest.stiffness.norm());
  Eigen::SelfAdjointEigenSolver<P2Matrix> eigen(rest.stiffness);
  const auto& values = eigen.eigenvalues();  // ascending
  const double largest = values[29];
  for (int k = 0; k < 6; ++k) EXPECT_LT(std::abs(values[k]), 1e-10 * largest);
  EXPECT_GT(values[6], 1e-4 * largest);
}

// The packed K_e (what a body stores) multiplies as the full matrix does, and holds its blocks.
TEST(P2PackedStiffness, MultipliesAsTheFullMatrix) {
  std::mt19937 rng(10);
  const P2Nodes X = MakeStraightP2Nodes(RandomCorners(&rng));
  const QuadraticTetRest rest = MakeQuadraticTetRest(X, kMu, kLambda, kRho);
  const P2PackedStiffness packed = PackP2Stiffness(rest.stiffness);
  EXPECT_TRUE((packed.blocks[1] == rest.stiffness.block<3, 3>(0, 3)));     // pair (0, 1)
  EXPECT_TRUE((packed.blocks[10] == rest.stiffness.block<3, 3>(3, 3)));    // pair (1, 1)
  EXPECT_TRUE((packed.blocks[54] == rest.stiffness.block<3, 3>(27, 27)));  // pair (9, 9)
  for (int trial = 0; trial < 3; ++trial) {
    const P2Vector u = P2Vector::Random();
    const P2Vector full = rest.stiffness * u;
    EXPECT_LT((MultiplyPackedStiffness(packed, u) - full).norm(), 1e-13 * full.norm());
  }
}

// f = −∂E/∂x with R held fixed, by central differences of the energy at a deformed state.
TEST(QuadraticTetForce, IsMinusTheGradientOfTheEnergy) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const P2Nodes X = MakeStraightP2Nodes(RandomCorners(&rng));
  const QuadraticTetRest rest = MakeQuadraticTetRest(X, kMu, kLambda, kRho);
  P2Nodes x = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 2).normalized()).toRotationMatrix() * X;
  for (int a = 0; a < kP2Nodes; ++a)
    for (int r = 0; r < 3; ++r) x(r, a) += 5e-4 * unit(rng);
  const Eigen::Matrix3d R = CalcQuadraticTetRotation(rest, x);
  const P2Vector f = CalcQuadraticTetForce(rest, X, x, R);
  constexpr double h = 1e-7;
  double worst = 0.0;
  for (int a = 0; a < kP2Nodes; ++a)
    for (int r = 0; r < 3; ++r) {
      P2Nodes plus = x, minus = x;
      plus(r, a) += h;
      minus(r, a) -= h;
      const double dE =
          (CalcQuadraticTetEnergy(rest, X, plus, R) - CalcQuadraticTetEnergy(rest, X, minus, R)) /
          (2 * h);
      worst = std::max(worst, std::abs(f[3 * a + r] + dE));
    }
  EXPECT_LT(worst, 1e-6 * f.cwiseAbs().maxCoeff());
  EXPECT_GT(f.norm(), 0.0);
}

TEST(QuadraticTetForce, ARigidMotionProducesNoForce) {
  std::mt19937 rng(13);
  const P2Nodes X = MakeStraightP2Nodes(RandomCorners(&rng));
  const QuadraticTetRest rest = MakeQuadraticTetRest(X, kMu, kLambda, kRho);
  for (const double angle : {0.3, 1.7, 3.0}) {
    const Eigen::Matrix3d Q =
        Eigen::AngleAxisd(angle, Eigen::Vector3d(0.3, -1, 0.5).normalized()).toRotationMatrix();
    const P2Nodes x = (Q * X).colwise() + Eigen::Vector3d(0.1, -0.2, 0.05);
    const Eigen::Matrix3d R = CalcQuadraticTetRotation(rest, x);
    EXPECT_LT((R - Q).norm(), 1e-12) << angle;
    // Against the force of a 1 % strain, which the same element does feel.
    const P2Nodes strained = 1.01 * X;
    const double felt =
        CalcQuadraticTetForce(rest, X, strained, Eigen::Matrix3d::Identity()).norm();
    EXPECT_LT(CalcQuadraticTetForce(rest, X, x, R).norm(), 1e-10 * felt) << angle;
  }
}

// ∫ N_a = −V/20 at a corner and V/5 at an edge node (closed form), so row-sum lumping would give
// negative masses; HRZ keeps every mass positive and the total ρV.
TEST(QuadraticTetRest, MassIsRhoVPositiveWhereRowSumsAreNot) {
  std::mt19937 rng(17);
  const P2Nodes X = MakeStraightP2Nodes(RandomCorners(&rng));
  const QuadraticTetRest rest = MakeQuadraticTetRest(X, kMu, kLambda, kRho);
  const double mass = kRho * rest.volume_m3;
  const auto M = CalcP2ConsistentMass(X, kRho);
  EXPECT_NEAR(M.sum(), mass, 1e-13 * mass);
  for (int a = 0; a < kP2Nodes; ++a)
    EXPECT_NEAR(M.row(a).sum(), a < 4 ? -mass / 20.0 : mass / 5.0, 1e-13 * mass) << a;
  EXPECT_NEAR(rest.lumped_mass_kg.sum(), mass, 1e-13 * mass);
  EXPECT_GT(rest.lumped_mass_kg.minCoeff(), 0.0);
  // The consistent diagonal in closed form: ρV/70 at a corner, 8ρV/105 at an edge node (∫ N_a²;
  // 18ρV/35 in all), so HRZ gives each corner 1/36 and each edge node 4/27 of the mass.
  for (int a = 0; a < kP2Nodes; ++a)
    EXPECT_NEAR(rest.lumped_mass_kg[a], mass * (a < 4 ? 1.0 / 36.0 : 4.0 / 27.0), 1e-13 * mass);
}

TEST(FindQuadraticTetProblem, RefusesInvertedAndFoldedElements) {
  const Eigen::Matrix<double, 3, 4> corners =
      (Eigen::Matrix<double, 3, 4>() << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1).finished() * 0.01;
  const P2Nodes straight = MakeStraightP2Nodes(corners);
  EXPECT_FALSE(FindQuadraticTetProblem(straight).has_value());
  // A moderately curved element is fine.
  P2Nodes curved = straight;
  curved.col(4) += Eigen::Vector3d(0, -0.001, -0.001);
  EXPECT_FALSE(FindQuadraticTetProblem(curved).has_value());
  // An edge node pushed past a quarter of its edge towards one end folds the mapping there.
  P2Nodes folded = straight;
  folded.col(4) = 0.2 * corners.col(0) + 0.8 * corners.col(1);
  ASSERT_TRUE(FindQuadraticTetProblem(folded).has_value());
  EXPECT_NE(FindQuadraticTetProblem(folded)->find("edge node"), std::string::npos);
  EXPECT_THROW(MakeQuadraticTetRest(folded, kMu, kLambda, kRho), std::invalid_argument);
  // Inverted: two corners swapped.
  P2Nodes inverted = MakeStraightP2Nodes(corners(Eigen::all, {0, 2, 1, 3}));
  EXPECT_TRUE(FindQuadraticTetProblem(inverted).has_value());
}

// Patch tests on an assembled mesh: the cube [0, 2 cm]³ in 8 cells of 6 tets each (48 P2
// elements, 125 nodes, 27 of them inside). The exact field is imposed on the boundary nodes and
// K u = F solved for the inside ones: a linear field with no load, and a quadratic field with
// its body force f = −div σ (constant), whose load is ∫ N_a f dV. P2 reproduces both exactly.
struct P2Mesh {
  std::vector<Eigen::Vector3d> nodes;
  std::vector<std::array<int, kP2Nodes>> tets;
};

P2Mesh MakeCubeMesh() {
  P2Mesh mesh;
  std::map<std::array<long, 3>, int> index;  // node by position in half-cells (exact integers)
  const double half = 0.005;                 // m: a cell is 1 cm, a half-cell 5 mm
  const auto node = [&](const Eigen::Vector3d& x) {
    const std::array<long, 3> key = {std::lround(x[0] / half), std::lround(x[1] / half),
                                     std::lround(x[2] / half)};
    const auto [it, added] = index.emplace(key, static_cast<int>(mesh.nodes.size()));
    if (added) mesh.nodes.push_back(x);
    return it->second;
  };
  // Kuhn's six tets of a cell: paths from corner 000 to 111 through the axes in each order.
  const int orders[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int k = 0; k < 2; ++k)
        for (const auto& order : orders) {
          Eigen::Matrix<double, 3, 4> corners;
          Eigen::Vector3d x(i, j, k);
          corners.col(0) = 0.01 * x;
          for (int s = 0; s < 3; ++s) {
            x[order[s]] += 1.0;
            corners.col(s + 1) = 0.01 * x;
          }
          Eigen::Matrix3d D;
          for (int s = 0; s < 3; ++s) D.col(s) = corners.col(s + 1) - corners.col(0);
          if (D.determinant() < 0) corners.col(1).swap(corners.col(2));
          const P2Nodes X = MakeStraightP2Nodes(corners);
          std::array<int, kP2Nodes> tet;
          for (int a = 0; a < kP2Nodes; ++a) tet[a] = node(X.col(a));
          mesh.tets.push_back(tet);
        }
  return mesh;
}

// Solves the inside nodes for boundary values u_exact and nodal loads, returns the worst error.
double SolvePatch(const P2Mesh& mesh,
                  const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& u_exact,
                  const Eigen::Vector3d& body_force_N_m3) {
  const int n = static_cast<int>(mesh.nodes.size());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(3 * n, 3 * n);
  Eigen::VectorXd F = Eigen::VectorXd::Zero(3 * n);
  for (const auto& tet : mesh.tets) {
    P2Nodes X;
    for (int a = 0; a < kP2Nodes; ++a) X.col(a) = mesh.nodes[tet[a]];
    const QuadraticTetRest rest = MakeQuadraticTetRest(X, kMu, kLambda, kRho);
    // ∫ N_a dV: −V/20 at the corners, V/5 at the edge nodes (straight elements).
    for (int a = 0; a < kP2Nodes; ++a) {
      for (int b = 0; b < kP2Nodes; ++b)
        K.block<3, 3>(3 * tet[a], 3 * tet[b]) += rest.stiffness.block<3, 3>(3 * a, 3 * b);
      F.segment<3>(3 * tet[a]) += (a < 4 ? -0.05 : 0.2) * rest.volume_m3 * body_force_N_m3;
    }
  }
  std::vector<int> inside, boundary;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& x = mesh.nodes[i];
    const bool on_boundary = (x.array() < 1e-9).any() || (x.array() > 0.02 - 1e-9).any();
    for (int d = 0; d < 3; ++d) (on_boundary ? boundary : inside).push_back(3 * i + d);
  }
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * n);
  for (int i = 0; i < n; ++i) u.segment<3>(3 * i) = u_exact(mesh.nodes[i]);
  const Eigen::VectorXd rhs = F(inside) - K(inside, boundary) * u(boundary);
  const Eigen::VectorXd u_inside = K(inside, inside).ldlt().solve(rhs);
  EXPECT_EQ(inside.size(), 3u * 27u);
  return (u_inside - u(inside)).cwiseAbs().maxCoeff() / u.cwiseAbs().maxCoeff();
}

TEST(QuadraticTetPatch, ReproducesALinearAndAQuadraticFieldExactly) {
  const P2Mesh mesh = MakeCubeMesh();
  ASSERT_EQ(mesh.nodes.size(), 125u);
  ASSERT_EQ(mesh.tets.size(), 48u);
  const Eigen::Matrix3d A = 1e-2 * Eigen::Matrix3d::Random();
  const Eigen::Vector3d c(1e-4, -2e-4, 3e-4);
  EXPECT_LT(SolvePatch(
                mesh, [&](const Eigen::Vector3d& x) { return Eigen::Vector3d(A * x + c); },
                Eigen::Vector3d::Zero()),
            1e-10);
  // u_i = xᵀ H_i x: div σ_i = μ tr(H''_i) + (μ + λ) Σ_l H''_l(i, l), H'' = 2 H the Hessians.
  std::array<Eigen::Matrix3d, 3> H;
  for (Eigen::Matrix3d& h : H) {
    h = Eigen::Matrix3d::Random();
    h = 0.5 * (h + h.transpose()).eval();
  }
  Eigen::Vector3d div_sigma;
  for (int i = 0; i < 3; ++i) {
    double mixed = 0.0;
    for (int l = 0; l < 3; ++l) mixed += 2.0 * H[l](i, l);
    div_sigma[i] = kMu * 2.0 * H[i].trace() + (kMu + kLambda) * mixed;
  }
  const auto quadratic = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(x.dot(H[0] * x), x.dot(H[1] * x), x.dot(H[2] * x));
  };
  EXPECT_LT(SolvePatch(mesh, quadratic, -div_sigma), 1e-9);
  // Without the body force the same boundary values give another field: the test can fail.
  EXPECT_GT(SolvePatch(mesh, quadratic, Eigen::Vector3d::Zero()), 1e-3);
}

}  // namespace
}  // namespace hapsim::fem
