#include "fem/quadratic_tet.h"

#include <Eigen/Dense>
#include <cstdio>
#include <stdexcept>

#include "fem/polar_decomposition.h"

namespace hapsim::fem {
namespace {

// The points of a symmetric tet rule: all distinct permutations of the barycentric coordinates
// (a, a, a, 1 − 3a) or (a, a, b, b) with b = 1/2 − a; ξ = (L_1, L_2, L_3).
void AddOrbit4(double a, double weight, std::array<QuadraturePoint, 14>* rule, int* next) {
  const double b = 1.0 - 3.0 * a;
  for (int k = 0; k < 4; ++k) {
    double L[4] = {a, a, a, a};
    L[k] = b;
    (*rule)[(*next)++] = {Eigen::Vector3d(L[1], L[2], L[3]), weight};
  }
}
void AddOrbit6(double a, double weight, std::array<QuadraturePoint, 14>* rule, int* next) {
  const double b = 0.5 - a;
  for (const auto& [i, j] : kP2EdgeCorners) {
    double L[4] = {b, b, b, b};
    L[i] = a;
    L[j] = a;
    (*rule)[(*next)++] = {Eigen::Vector3d(L[1], L[2], L[3]), weight};
  }
}

// Barycentric coordinates of ξ and their (constant) derivatives ∂L/∂ξ.
Eigen::Vector4d Barycentric(const Eigen::Vector3d& xi) {
  return Eigen::Vector4d(1.0 - xi.sum(), xi[0], xi[1], xi[2]);
}
Eigen::Matrix<double, 4, 3> BarycentricDerivatives() {
  Eigen::Matrix<double, 4, 3> dL;
  dL << -1, -1, -1, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  return dL;
}

// J = ∂x/∂ξ = Σ_a X_a (∂N_a/∂ξ)ᵀ.
Eigen::Matrix3d CalcJacobian(const P2Nodes& X_m, const Eigen::Matrix<double, kP2Nodes, 3>& dN) {
  return X_m * dN;
}

}  // namespace

const std::array<QuadraturePoint, 14>& P2Quadrature() {
  // The classical symmetric 14-point rule of degree 5 with positive weights: orbits of 4, 4 and
  // 6 points. Weights for the volume 1/6; tests/fem/quadratic_tet_test.cc checks it on all 126
  // monomials of degree ≤ 5 against their closed form.
  static const std::array<QuadraturePoint, 14> rule = [] {
    std::array<QuadraturePoint, 14> r{};
    int next = 0;
    AddOrbit4(0.0927352503108912264, 0.0122488405193936582, &r, &next);
    AddOrbit4(0.3108859192633006098, 0.0187813209530026417, &r, &next);
    AddOrbit6(0.4544962958743503744, 0.0070910034628469110, &r, &next);
    return r;
  }();
  return rule;
}

Eigen::Matrix<double, kP2Nodes, 1> CalcP2ShapeFunctions(const Eigen::Vector3d& xi) {
  const Eigen::Vector4d L = Barycentric(xi);
  Eigen::Matrix<double, kP2Nodes, 1> N;
  for (int i = 0; i < 4; ++i) N[i] = L[i] * (2.0 * L[i] - 1.0);
  for (int k = 0; k < 6; ++k) N[4 + k] = 4.0 * L[kP2EdgeCorners[k][0]] * L[kP2EdgeCorners[k][1]];
  return N;
}

Eigen::Matrix<double, kP2Nodes, 3> CalcP2ShapeDerivatives(const Eigen::Vector3d& xi) {
  const Eigen::Vector4d L = Barycentric(xi);
  const Eigen::Matrix<double, 4, 3> dL = BarycentricDerivatives();
  Eigen::Matrix<double, kP2Nodes, 3> dN;
  for (int i = 0; i < 4; ++i) dN.row(i) = (4.0 * L[i] - 1.0) * dL.row(i);
  for (int k = 0; k < 6; ++k) {
    const int i = kP2EdgeCorners[k][0], j = kP2EdgeCorners[k][1];
    dN.row(4 + k) = 4.0 * (L[j] * dL.row(i) + L[i] * dL.row(j));
  }
  return dN;
}

std::optional<std::string> FindQuadraticTetProblem(const P2Nodes& X_m) {
  if (!X_m.allFinite()) return std::string("a node position is not finite");
  // The scale of det J: the corner tet's edges cubed.
  const double edge = (X_m.col(1) - X_m.col(0)).norm() + (X_m.col(2) - X_m.col(0)).norm() +
                      (X_m.col(3) - X_m.col(0)).norm();
  const double scale = std::pow(edge / 3.0, 3);
  const auto check = [&](const Eigen::Vector3d& xi,
                         const char* where) -> std::optional<std::string> {
    const double det = CalcJacobian(X_m, CalcP2ShapeDerivatives(xi)).determinant();
    if (det > 1e-9 * scale) return std::nullopt;
    char text[160];
    std::snprintf(
        text, sizeof(text),
        "det(dx/dxi) = %.3g m^3 at %s (xi %.3f %.3f %.3f): the element is inverted, flat, "
        "or an edge node is far off its edge's midpoint",
        det, where, xi[0], xi[1], xi[2]);
    return std::string(text);
  };
  const Eigen::Vector3d corners[4] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(),
                                      Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  for (const Eigen::Vector3d& xi : corners)
    if (auto problem = check(xi, "a corner")) return problem;
  for (const QuadraturePoint& q : P2Quadrature())
    if (auto problem = check(q.xi, "a quadrature point")) return problem;
  return std::nullopt;
}

Eigen::Matrix<double, kP2Nodes, kP2Nodes> CalcP2ConsistentMass(const P2Nodes& X_m,
                                                               double density_kg_m3) {
  Eigen::Matrix<double, kP2Nodes, kP2Nodes> M = Eigen::Matrix<double, kP2Nodes, kP2Nodes>::Zero();
  for (const QuadraturePoint& q : P2Quadrature()) {
    const auto N = CalcP2ShapeFunctions(q.xi);
    const double dV = q.weight * CalcJacobian(X_m, CalcP2ShapeDerivatives(q.xi)).determinant();
    M.noalias() += density_kg_m3 * dV * N * N.transpose();
  }
  return M;
}

QuadraticTetRest MakeQuadraticTetRest(const P2Nodes& X_m, double lame_mu_Pa, double lame_lambda_Pa,
                                      double density_kg_m3) {
  if (auto problem = FindQuadraticTetProblem(X_m)) throw std::invalid_argument(*problem);
  QuadraticTetRest rest;
  for (const QuadraturePoint& q : P2Quadrature()) {
    const Eigen::Matrix<double, kP2Nodes, 3> dN = CalcP2ShapeDerivatives(q.xi);
    const Eigen::Matrix3d J = CalcJacobian(X_m, dN);
    const double dV = q.weight * J.determinant();
    // g_a = ∂N_a/∂X = J⁻ᵀ ∂N_a/∂ξ, as the columns of g.
    const Eigen::Matrix<double, 3, kP2Nodes> g = J.transpose().inverse() * dN.transpose();
    const Eigen::Matrix<double, kP2Nodes, kP2Nodes> gram = g.transpose() * g;
    for (int a = 0; a < kP2Nodes; ++a)
      for (int b = 0; b < kP2Nodes; ++b) {
        Eigen::Matrix3d block = lame_mu_Pa * g.col(b) * g.col(a).transpose() +
                                lame_lambda_Pa * g.col(a) * g.col(b).transpose();
        block.diagonal().array() += lame_mu_Pa * gram(a, b);
        rest.stiffness.block<3, 3>(3 * a, 3 * b) += dV * block;
      }
    rest.volume_m3 += dV;
  }
  // HRZ: the consistent diagonal, scaled to the element's mass.
  const Eigen::Matrix<double, kP2Nodes, 1> diagonal =
      CalcP2ConsistentMass(X_m, density_kg_m3).diagonal();
  rest.lumped_mass_kg = diagonal * (density_kg_m3 * rest.volume_m3 / diagonal.sum());
  // The corner tet's P1 gradients: the rows of D_m⁻¹, and b_0 = −(b_1 + b_2 + b_3).
  Eigen::Matrix3d D_m;
  for (int k = 0; k < 3; ++k) D_m.col(k) = X_m.col(k + 1) - X_m.col(0);
  const Eigen::Matrix3d D_inv = D_m.inverse();
  for (int k = 0; k < 3; ++k) rest.corner_gradients_1_m.col(k + 1) = D_inv.row(k).transpose();
  rest.corner_gradients_1_m.col(0) = -rest.corner_gradients_1_m.rightCols<3>().rowwise().sum();
  return rest;
}

Eigen::Matrix3d CalcQuadraticTetRotation(const QuadraticTetRest& rest, const P2Nodes& x_m) {
  return CalcRotationOfDeformation(x_m.leftCols<4>() * rest.corner_gradients_1_m.transpose());
}

namespace {
// Rᵀ x − X, node-major.
P2Vector CalcCorotatedDisplacement(const P2Nodes& X_m, const P2Nodes& x_m,
                                   const Eigen::Matrix3d& rotation) {
  const P2Nodes u = rotation.transpose() * x_m - X_m;
  return Eigen::Map<const P2Vector>(u.data());
}
}  // namespace

P2Vector CalcQuadraticTetForce(const QuadraticTetRest& rest, const P2Nodes& X_m, const P2Nodes& x_m,
                               const Eigen::Matrix3d& rotation) {
  const P2Vector local = rest.stiffness * CalcCorotatedDisplacement(X_m, x_m, rotation);
  P2Vector force;
  for (int a = 0; a < kP2Nodes; ++a) force.segment<3>(3 * a) = -rotation * local.segment<3>(3 * a);
  return force;
}

double CalcQuadraticTetEnergy(const QuadraticTetRest& rest, const P2Nodes& X_m, const P2Nodes& x_m,
                              const Eigen::Matrix3d& rotation) {
  const P2Vector u = CalcCorotatedDisplacement(X_m, x_m, rotation);
  return 0.5 * u.dot(rest.stiffness * u);
}

P2PackedStiffness PackP2Stiffness(const P2Matrix& stiffness) {
  P2PackedStiffness packed;
  int pair = 0;
  for (int a = 0; a < kP2Nodes; ++a)
    for (int b = a; b < kP2Nodes; ++b, ++pair)
      packed.blocks[pair] = stiffness.block<3, 3>(3 * a, 3 * b);
  return packed;
}

P2Vector MultiplyPackedStiffness(const P2PackedStiffness& stiffness, const P2Vector& u) {
  P2Vector product = P2Vector::Zero();
  int pair = 0;
  for (int a = 0; a < kP2Nodes; ++a) {
    product.segment<3>(3 * a) += stiffness.blocks[pair++] * u.segment<3>(3 * a);
    for (int b = a + 1; b < kP2Nodes; ++b, ++pair) {
      const Eigen::Matrix3d& block = stiffness.blocks[pair];  // K_ab; K_ba is its transpose
      product.segment<3>(3 * a) += block * u.segment<3>(3 * b);
      product.segment<3>(3 * b) += block.transpose() * u.segment<3>(3 * a);
    }
  }
  return product;
}

P2Nodes MakeStraightP2Nodes(const Eigen::Matrix<double, 3, 4>& corners_m) {
  P2Nodes X;
  X.leftCols<4>() = corners_m;
  for (int k = 0; k < 6; ++k)
    X.col(4 + k) =
        0.5 * (corners_m.col(kP2EdgeCorners[k][0]) + corners_m.col(kP2EdgeCorners[k][1]));
  return X;
}

}  // namespace hapsim::fem
