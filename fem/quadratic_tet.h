#pragma once
// The 10-node (quadratic, P2) tetrahedron (issue 27): shape functions, quadrature, the element
// stiffness and mass at rest, and its corotational force. A body of them (`element: p2`,
// fem/model.h) stores each tet's K_e and HRZ masses from here.
//
// Nodes, in Gmsh's order for its element type 11: the corners 0–3, then one node on each edge,
//   4: (0,1)  5: (1,2)  6: (2,0)  7: (3,0)  8: (3,2)  9: (3,1).
// With barycentric coordinates L_0..L_3 of the reference tet (L_0 = 1 − ξ1 − ξ2 − ξ3, L_k = ξ_k),
//   corner i:       N_i = L_i (2 L_i − 1)
//   edge (i, j):    N   = 4 L_i L_j,
// which interpolate quadratic fields exactly. Geometry is isoparametric: x(ξ) = Σ N_a(ξ) X_a,
// so an element whose edge nodes are moved off their midpoints (onto a curved surface) is curved.
//
// Stiffness. K_e = ∫ Bᵀ D B dV, block (a, b) = ∫ [μ (g_a·g_b) I + μ g_b g_aᵀ + λ g_a g_bᵀ] dV with
// g = ∂N/∂X, as the linear tet's (fem/stiffness_assembly.h) but with gradients that vary over the
// element. For a straight element the integrand is quadratic, and the 14-point rule below
// (degree 5) integrates it exactly; so it does the consistent mass (degree 4).
//
// Mass. The row sums of P2's consistent mass are negative at the corners (−ρV/20 each; ρV/5 at
// each edge node), so row-sum lumping is unusable. HRZ lumping (Hinton, Rock & Zienkiewicz 1976)
// keeps the consistent diagonal scaled to the element's mass: positive at every node.
//
// Corotation. The element's rotation is that of its corner tet, R = polar(Σ_{i<4} x_i b_iᵀ) with
// b_i the rest corner tet's P1 gradients (fem/model.h TetRestData), exactly the linear tet's: the
// batched polar decomposition, the node rotations of the warped compliance and the inversion
// handling serve P2 bodies unchanged. A rigid motion of all ten nodes rotates the corner tet by
// the same R, so it produces no force. Force f_e = −R K_e (Rᵀ x_e − X_e), the gradient of
// E_e = ½ (Rᵀ x_e − X_e)ᵀ K_e (Rᵀ x_e − X_e) with R held fixed, as for linear tets.

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>

namespace hapsim::fem {

inline constexpr int kP2Nodes = 10;
// The corners joined by edge node 4 + k.
inline constexpr std::array<std::array<int, 2>, 6> kP2EdgeCorners = {
    {{0, 1}, {1, 2}, {2, 0}, {3, 0}, {3, 2}, {3, 1}}};

// The edge k (0..5) joining corners i and j, either way round.
constexpr int FindP2Edge(int i, int j) {
  for (int k = 0; k < 6; ++k)
    if ((kP2EdgeCorners[k][0] == i && kP2EdgeCorners[k][1] == j) ||
        (kP2EdgeCorners[k][0] == j && kP2EdgeCorners[k][1] == i))
      return k;
  return -1;
}

using P2Nodes = Eigen::Matrix<double, 3, kP2Nodes>;       // node positions, columns
using P2Vector = Eigen::Matrix<double, 3 * kP2Nodes, 1>;  // node-major, as the body's dofs
using P2Matrix = Eigen::Matrix<double, 3 * kP2Nodes, 3 * kP2Nodes>;

// K_e held as its node-pair blocks K_ab with a ≤ b, in the order (0,0) (0,1) … (0,9) (1,1) … (9,9):
// 55 blocks, 3.96 kB against the full matrix's 7.2 kB (K_ba = K_abᵀ). A body stores its tets' K_e
// so: the two passes that read every K_e each step, assembly and the elastic force, were bound by
// reading them (at 1.7k tets the 12 MB of full matrices is more than the caches hold), and the
// pair order is the order assembly writes the blocks in (fem/stiffness_assembly.h).
inline constexpr int kP2NodePairs = kP2Nodes * (kP2Nodes + 1) / 2;
struct P2PackedStiffness {
  std::array<Eigen::Matrix3d, kP2NodePairs> blocks;
};
P2PackedStiffness PackP2Stiffness(const P2Matrix& stiffness);
// K_e u with K_e packed: each off-diagonal block serves both its pair's products.
P2Vector MultiplyPackedStiffness(const P2PackedStiffness& stiffness, const P2Vector& u);

// A point of the reference tet with its weight (the weights sum to the reference volume 1/6).
struct QuadraturePoint {
  Eigen::Vector3d xi;
  double weight;
};
// 14 points, positive weights, exact for polynomials of degree ≤ 5 (a symmetric rule).
const std::array<QuadraturePoint, 14>& P2Quadrature();

// N_a(ξ) for the ten nodes.
Eigen::Matrix<double, kP2Nodes, 1> CalcP2ShapeFunctions(const Eigen::Vector3d& xi);
// ∂N_a/∂ξ (row a).
Eigen::Matrix<double, kP2Nodes, 3> CalcP2ShapeDerivatives(const Eigen::Vector3d& xi);

// The element's rest data: its stiffness and mass for the Lamé constants and density given.
struct QuadraticTetRest {
  P2Matrix stiffness = P2Matrix::Zero();  // K_e, N/m
  // m_a, kg: HRZ-lumped, positive, Σ m_a = ρV.
  Eigen::Matrix<double, kP2Nodes, 1> lumped_mass_kg = Eigen::Matrix<double, kP2Nodes, 1>::Zero();
  Eigen::Matrix<double, 3, 4> corner_gradients_1_m;  // b_0..b_3 of the corner tet (corotation)
  double volume_m3 = 0.0;                            // ∫ dV (of the curved element)
};

// Describes why the element cannot be used at rest (det ∂x/∂ξ ≤ 0 at a corner or a quadrature
// point: inverted, flat, or an edge node so far off its edge's midpoint that the mapping folds),
// or nullopt. Checking the corners and the 14 points is what the quadrature relies on; it is not
// a proof that det J > 0 everywhere inside a strongly curved element.
std::optional<std::string> FindQuadraticTetProblem(const P2Nodes& X_m);

// K_e, HRZ masses, corner gradients and volume. Throws std::invalid_argument on
// FindQuadraticTetProblem's problems.
QuadraticTetRest MakeQuadraticTetRest(const P2Nodes& X_m, double lame_mu_Pa, double lame_lambda_Pa,
                                      double density_kg_m3);

// The consistent mass matrix ρ ∫ N_a N_b dV (10 × 10, per axis), kg: for tests and HRZ.
Eigen::Matrix<double, kP2Nodes, kP2Nodes> CalcP2ConsistentMass(const P2Nodes& X_m,
                                                               double density_kg_m3);

// The corner tet's rotation at positions x (CalcRotationOfDeformation of Σ_{i<4} x_i b_iᵀ).
Eigen::Matrix3d CalcQuadraticTetRotation(const QuadraticTetRest& rest, const P2Nodes& x_m);

// Corotational elastic force −R K_e (Rᵀ x − X) on the ten nodes (node-major), N, and energy, J.
P2Vector CalcQuadraticTetForce(const QuadraticTetRest& rest, const P2Nodes& X_m, const P2Nodes& x_m,
                               const Eigen::Matrix3d& rotation);
double CalcQuadraticTetEnergy(const QuadraticTetRest& rest, const P2Nodes& X_m, const P2Nodes& x_m,
                              const Eigen::Matrix3d& rotation);

// Straight P2 nodes of a linear tet: the corners and the midpoints of its edges.
P2Nodes MakeStraightP2Nodes(const Eigen::Matrix<double, 3, 4>& corners_m);

}  // namespace hapsim::fem
