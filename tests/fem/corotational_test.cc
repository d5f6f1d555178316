// Corotational elasticity and warped stiffness against independent values: exact rotation
// invariance (and the ghost forces of linear FEM that lacks it), central differences of the force
// and of the energy, and a 12×12 element stiffness VBᵀDB built the textbook way. The polar
// decomposition has its own tests (polar_decomposition_test.cc).
#include "fem/corotational.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "fem/cg_solver.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/stiffness_assembly.h"
#include "tests/fem/test_utilities.h"

namespace hapsim::fem {
namespace {

using test::CalcElasticForceAt;
using test::Random;
using test::TransformPoints;

constexpr double kCell_m = 0.01;           // lattice cell edge ℓ
constexpr double kYoungsModulus_Pa = 1e5;  // E
constexpr double kPoissonRatio = 0.3;

Material MakeMaterial() {
  Material material;
  material.youngs_modulus_Pa = kYoungsModulus_Pa;
  material.poisson_ratio = kPoissonRatio;
  return material;
}

// A free 3 × 2 × 2-cell block (60 tets, 36 nodes).
Model MakeBlockModel() {
  return MakeModel(MakeBoxTetMesh({0, 0, 0}, {3 * kCell_m, 2 * kCell_m, 2 * kCell_m}, {3, 2, 2}),
                   MakeMaterial(), {});
}

Eigen::Matrix3d ArbitraryRotation() {
  return Eigen::AngleAxisd(2.1, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
}

Eigen::MatrixXd AssembleDense(const Model& model, const std::vector<Eigen::Matrix3d>& rotations) {
  const StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(model, rotations, /*scale=*/1.0, &K);
  return Eigen::MatrixXd(Eigen::SparseMatrix<double>(K.selfadjointView<Eigen::Lower>()));
}

// ---------------------------------------------------------------------------------------------
// 1. Rotation invariance.

// A rigidly moved rest shape has F = R exactly, so the corotational strain is zero to round-off:
// ~1e-16 · |x|/ℓ ≈ 1e-14 in F, far below 1e-9 of the force scale E ℓ ‖x − X‖.
constexpr double kRigidMotionRelativeForce = 1e-9;
// Polar rotation of F = R: the Newton iteration starts at its fixed point, so R_e = R to round-off.
constexpr double kRigidMotionRotationError = 1e-12;

TEST(Corotational, RigidMotionGivesNoForceButLinearFemGivesGhostForces) {
  const Model model = MakeBlockModel();
  const Eigen::Vector3d t_m(0.1, -0.2, 0.05);
  const std::vector<Eigen::Matrix3d> rotations = {
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix(),
      ArbitraryRotation()};
  for (const Eigen::Matrix3d& R : rotations) {
    const Eigen::VectorXd x_m = TransformPoints(R, t_m, model.rest_positions_m);
    // ‖K‖ per node is ~E ℓ, so E ℓ ‖x − X‖ bounds the force a displacement x − X could produce.
    const double force_scale_N =
        kYoungsModulus_Pa * kCell_m * (x_m - model.rest_positions_m).norm();

    std::vector<Eigen::Matrix3d> element_rotations;
    CalcElementRotations(model, x_m, ElasticityKind::kCorotational, &element_rotations);
    for (const Eigen::Matrix3d& R_e : element_rotations)
      EXPECT_LE((R_e - R).norm(), kRigidMotionRotationError);
    const Eigen::VectorXd corotational_N =
        CalcElasticForceAt(model, x_m, ElasticityKind::kCorotational);
    const Eigen::VectorXd linear_N = CalcElasticForceAt(model, x_m, ElasticityKind::kLinear);
    EXPECT_LE(corotational_N.norm(), kRigidMotionRelativeForce * force_scale_N);
    EXPECT_LE(CalcElasticEnergy(model, x_m, element_rotations),
              kRigidMotionRelativeForce * kYoungsModulus_Pa * std::pow(kCell_m, 3));
    // Linear FEM reads a rotation by θ as a strain of order 1 − cos θ ≥ 0.5 for these rotations,
    // a stress of order E, hence ghost forces of order E ℓ² on the boundary nodes.
    EXPECT_GT(linear_N.norm(), 0.1 * kYoungsModulus_Pa * kCell_m * kCell_m);
    std::printf(
        "rotation angle %.3f rad: corotational |f| = %.3e N, linear |f| = %.3e N "
        "(force scale %.3e N)\n",
        Eigen::AngleAxisd(R).angle(), corotational_N.norm(), linear_N.norm(), force_scale_N);
  }
  // A pure translation is harmless to both.
  const Eigen::VectorXd translated_m =
      TransformPoints(Eigen::Matrix3d::Identity(), t_m, model.rest_positions_m);
  const double translation_scale_N =
      kYoungsModulus_Pa * kCell_m * (translated_m - model.rest_positions_m).norm();
  EXPECT_LE(CalcElasticForceAt(model, translated_m, ElasticityKind::kLinear).norm(),
            kRigidMotionRelativeForce * translation_scale_N);
}

// ---------------------------------------------------------------------------------------------
// 2. Finite differences of force and energy.

// Central differences with step ε = 1e-6 ℓ: truncation ~(ε/ℓ)² = 1e-12, round-off in the force
// ~1e-16 / (ε/ℓ) ≈ 1e-10 relative, and the ≤ 5e-13 the polar Newton iteration leaves in R_e (it
// may stop at a different iteration at x ± εδ) contributes ≲ 5e-13 · η / (ε/ℓ) ≤ 5e-10 for
// η ≤ 1e-3. Measured 1.5e-10 to 2.6e-10 at rest; 1e-6 leaves ample margin.
constexpr double kFdStep = 1e-6;
constexpr double kFdRelativeTolerance = 1e-6;
// The warped stiffness omits ∂R/∂x. The omitted part of df, dR K_e(Rᵀx − X) and R K_e dRᵀ x
// (whose rigid part K_e W X vanishes), is (strain) × ‖K dx‖: relative error ≤ C·η for a
// perturbation of relative size η, with C ≈ 0.3–0.4 measured here; 2 bounds it. A missing
// first-order term in K would give an error of order 1 instead.
constexpr double kOmittedRotationDerivativeFactor = 2.0;

// ‖K δ − (−∂f/∂x δ)‖ / ‖K δ‖ at positions x, with ∂f/∂x by central differences of the true
// corotational force (rotations recomputed at each position).
double StiffnessDirectionalError(const Model& model, const Eigen::VectorXd& x_m,
                                 ElasticityKind kind, const Eigen::VectorXd& direction) {
  std::vector<Eigen::Matrix3d> rotations;
  CalcElementRotations(model, x_m, kind, &rotations);
  const StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(model, rotations, /*scale=*/1.0, &K);
  const Eigen::VectorXd K_delta = K.selfadjointView<Eigen::Lower>() * direction;
  const double step_m = kFdStep * kCell_m;
  const Eigen::VectorXd fd = -(CalcElasticForceAt(model, x_m + step_m * direction, kind) -
                               CalcElasticForceAt(model, x_m - step_m * direction, kind)) /
                             (2.0 * step_m);
  return (K_delta - fd).norm() / K_delta.norm();
}

TEST(Corotational, WarpedStiffnessMatchesCentralDifferencesNearRest) {
  const Model model = MakeBlockModel();
  Random random(7);
  const Eigen::VectorXd noise = random.Vector(model.num_dofs());
  const Eigen::VectorXd direction = random.Vector(model.num_dofs());
  const Eigen::Vector3d t_m(0.02, 0.03, -0.01);
  for (const Eigen::Matrix3d& R :
       {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), ArbitraryRotation()}) {
    std::vector<double> errors;
    for (double eta : {0.0, 1e-3, 1e-4}) {
      const Eigen::VectorXd x_m =
          TransformPoints(R, t_m, model.rest_positions_m + eta * kCell_m * noise);
      const double error =
          StiffnessDirectionalError(model, x_m, ElasticityKind::kCorotational, direction);
      std::printf("rotation angle %.2f, eta %.0e: |K d - FD| / |K d| = %.3e\n",
                  Eigen::AngleAxisd(R).angle(), eta, error);
      EXPECT_LE(error, std::max(kFdRelativeTolerance, kOmittedRotationDerivativeFactor * eta));
      errors.push_back(error);
    }
    // At rest the warped stiffness is the exact Jacobian; away from rest the mismatch is the
    // omitted ∂R/∂x term, first order in η: η ten times smaller gives an error ~ten times smaller.
    EXPECT_LE(errors[0], kFdRelativeTolerance);
    EXPECT_GT(errors[1], 10.0 * kFdRelativeTolerance);  // the omitted term is really there
    EXPECT_LT(errors[2], 0.2 * errors[1]);
  }
  // Linear FEM: K is the exact (constant) Jacobian even far from rest.
  const Eigen::VectorXd far_m = model.rest_positions_m + 0.2 * kCell_m * noise;
  EXPECT_LE(StiffnessDirectionalError(model, far_m, ElasticityKind::kLinear, direction),
            kFdRelativeTolerance);
}

// With the rotations held fixed the energy is quadratic in x, so central differences have no
// truncation error; round-off ε_mach E / (ε |∂E/∂x_i|) ≈ 1e-16 · η / (ε/ℓ) ≈ 1e-14 per entry for
// strain η = 0.05 and step ε = 1e-4 ℓ (measured 1e-12 to 3e-11 overall). Allow 1e-8.
constexpr double kEnergyFdStep = 1e-4;
constexpr double kEnergyFdRelativeTolerance = 1e-8;

TEST(Corotational, ForceIsMinusEnergyGradientWithRotationsHeld) {
  const Model model = MakeBlockModel();
  Random random(11);
  for (const Eigen::Matrix3d& R :
       {Eigen::Matrix3d(Eigen::Matrix3d::Identity()), ArbitraryRotation()}) {
    const Eigen::VectorXd x_m =
        TransformPoints(R, Eigen::Vector3d(0.01, 0.0, 0.02),
                        model.rest_positions_m + 0.05 * kCell_m * random.Vector(model.num_dofs()));
    for (ElasticityKind kind : {ElasticityKind::kCorotational, ElasticityKind::kLinear}) {
      std::vector<Eigen::Matrix3d> rotations;
      CalcElementRotations(model, x_m, kind, &rotations);
      Eigen::VectorXd force_N;
      CalcElasticForce(model, x_m, rotations, &force_N);
      const double step_m = kEnergyFdStep * kCell_m;
      Eigen::VectorXd gradient_fd(model.num_dofs());
      Eigen::VectorXd x_plus = x_m, x_minus = x_m;
      for (int i = 0; i < model.num_dofs(); ++i) {
        x_plus[i] += step_m;
        x_minus[i] -= step_m;
        gradient_fd[i] = (CalcElasticEnergy(model, x_plus, rotations) -
                          CalcElasticEnergy(model, x_minus, rotations)) /
                         (2.0 * step_m);
        x_plus[i] = x_minus[i] = x_m[i];
      }
      const double error = (force_N + gradient_fd).norm() / force_N.norm();
      std::printf("%s: |f + dE/dx| / |f| = %.3e\n", ToString(kind), error);
      EXPECT_LE(error, kEnergyFdRelativeTolerance);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 3. Warped stiffness: symmetry, rigid modes, and the textbook 12×12 element stiffness.

// Assembly and the two formulas below differ only in the order of floating-point operations.
constexpr double kAssemblyRoundOff = 1e-12;

TEST(WarpedStiffness, IsSymmetricWithRigidBodyNullSpace) {
  const Model model = MakeBlockModel();
  Random random(13);
  const Eigen::Matrix3d R = ArbitraryRotation();
  const Eigen::Vector3d t_m(0.3, 0.1, -0.2);
  const Eigen::VectorXd rigid_m = TransformPoints(R, t_m, model.rest_positions_m);
  const Eigen::VectorXd deformed_m = rigid_m + 0.1 * kCell_m * random.Vector(model.num_dofs());
  // Each R_e K_e R_eᵀ is positive semidefinite. Its null space holds the translations always,
  // and the infinitesimal rotations only when every R_eᵀ x_e is a rigid copy of X_e: six zero
  // eigenvalues at a rigidly moved rest shape, three once the elements rotate differently.
  for (const auto& [x_m, num_zero] : {std::pair(rigid_m, 6), std::pair(deformed_m, 3)}) {
    std::vector<Eigen::Matrix3d> rotations;
    CalcElementRotations(model, x_m, ElasticityKind::kCorotational, &rotations);
    const Eigen::MatrixXd K = AssembleDense(model, rotations);
    const double scale = K.cwiseAbs().maxCoeff();
    EXPECT_LE((K - K.transpose()).cwiseAbs().maxCoeff(), kAssemblyRoundOff * scale);
    const Eigen::VectorXd eigenvalues =
        Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(K).eigenvalues();
    const double zero = kAssemblyRoundOff * eigenvalues.maxCoeff();  // round-off of the eigensolver
    for (int i = 0; i < num_zero; ++i) EXPECT_LE(std::abs(eigenvalues[i]), zero) << i;
    EXPECT_GT(eigenvalues[num_zero], 1e-6 * eigenvalues.maxCoeff());
    std::printf("warped K with %d zero eigenvalues: smallest nonzero / largest = %.2e\n", num_zero,
                eigenvalues[num_zero] / eigenvalues.maxCoeff());
  }
  // At a rigidly moved rest shape the null space is the rigid motions of that shape:
  // translations and infinitesimal rotations ω × x.
  std::vector<Eigen::Matrix3d> rotations;
  CalcElementRotations(model, rigid_m, ElasticityKind::kCorotational, &rotations);
  const Eigen::MatrixXd K = AssembleDense(model, rotations);
  for (int axis = 0; axis < 3; ++axis) {
    Eigen::VectorXd translation(model.num_dofs()), rotation(model.num_dofs());
    for (int n = 0; n < model.num_nodes(); ++n) {
      translation.segment<3>(3 * n) = Eigen::Vector3d::Unit(axis);
      rotation.segment<3>(3 * n) =
          Eigen::Vector3d::Unit(axis).cross(Eigen::Vector3d(rigid_m.segment<3>(3 * n)));
    }
    EXPECT_LE((K * translation).norm(), kAssemblyRoundOff * K.norm() * translation.norm());
    EXPECT_LE((K * rotation).norm(), 1e-10 * K.norm() * rotation.norm());
  }
}

// Textbook element stiffness K_e = V Bᵀ D B (Voigt notation, engineering shear strains
// γ = 2ε), from the shape gradients b_a: a second method, unrelated to the block formula.
Eigen::Matrix<double, 12, 12> MakeTextbookElementStiffness(const TetRestData& rest,
                                                           const Material& m) {
  Eigen::Matrix<double, 6, 12> B = Eigen::Matrix<double, 6, 12>::Zero();
  for (int a = 0; a < 4; ++a) {
    const Eigen::Vector3d b = rest.shape_gradients_1_m.col(a);
    B(0, 3 * a + 0) = b.x();
    B(1, 3 * a + 1) = b.y();
    B(2, 3 * a + 2) = b.z();
    B(3, 3 * a + 1) = b.z(), B(3, 3 * a + 2) = b.y();  // γ_yz
    B(4, 3 * a + 0) = b.z(), B(4, 3 * a + 2) = b.x();  // γ_xz
    B(5, 3 * a + 0) = b.y(), B(5, 3 * a + 1) = b.x();  // γ_xy
  }
  const double E = m.youngs_modulus_Pa, nu = m.poisson_ratio;
  const double c = E / ((1.0 + nu) * (1.0 - 2.0 * nu));
  Eigen::Matrix<double, 6, 6> D = Eigen::Matrix<double, 6, 6>::Zero();
  D.topLeftCorner<3, 3>().setConstant(c * nu);
  D.topLeftCorner<3, 3>().diagonal().setConstant(c * (1.0 - nu));
  D.bottomRightCorner<3, 3>().diagonal().setConstant(c * (1.0 - 2.0 * nu) / 2.0);  // = μ
  return rest.volume_m3 * B.transpose() * D * B;
}

TEST(WarpedStiffness, EqualsRotatedTextbookElementStiffness) {
  Random random(17);
  TetMesh mesh;
  mesh.rest_positions_m.resize(3, 4);
  mesh.rest_positions_m << 0.0, 0.012, 0.001, 0.002,  //
      0.0, 0.001, 0.009, -0.001,                      //
      0.0, 0.002, 0.001, 0.011;
  mesh.tets.resize(4, 1);
  mesh.tets << 0, 1, 2, 3;
  const Model model = MakeModel(mesh, MakeMaterial(), {});
  // Textbook K_e is independent of how the block formula was derived; the rotation used is
  // arbitrary (the formulas hold for any R_e, not only the polar one).
  const Eigen::Matrix<double, 12, 12> K_e =
      MakeTextbookElementStiffness(model.tet_rest[0], model.material);
  // The same tet with its nodes listed in another order: local node a is global node
  // order[a], so the lower triangle receives blocks K_ab both as they are (a's node larger) and
  // transposed (b's larger). P maps local dofs to global ones.
  TetMesh permuted_mesh = mesh;
  const int order[4] = {2, 0, 3, 1};
  Eigen::Matrix<double, 12, 12> P = Eigen::Matrix<double, 12, 12>::Zero();
  for (int a = 0; a < 4; ++a) {
    permuted_mesh.tets(a, 0) = order[a];
    permuted_mesh.rest_positions_m.col(order[a]) = mesh.rest_positions_m.col(a);
    P.block<3, 3>(3 * order[a], 3 * a).setIdentity();
  }
  const Model permuted_model = MakeModel(permuted_mesh, MakeMaterial(), {});
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Matrix3d R = random.Rotation();
    Eigen::Matrix<double, 12, 12> R_big = Eigen::Matrix<double, 12, 12>::Zero();
    for (int a = 0; a < 4; ++a) R_big.block<3, 3>(3 * a, 3 * a) = R;
    const Eigen::MatrixXd K = AssembleDense(model, {R});
    const Eigen::Matrix<double, 12, 12> K_slow = R_big * K_e * R_big.transpose();
    EXPECT_LE((K - K_slow).norm(), kAssemblyRoundOff * K_slow.norm());
    const Eigen::MatrixXd K_permuted = AssembleDense(permuted_model, {R});
    EXPECT_LE((K_permuted - P * K_slow * P.transpose()).norm(), kAssemblyRoundOff * K_slow.norm());

    // Force f = −R K_e (Rᵀx − X) and energy ½ uᵀ K_e u with u = Rᵀx − X.
    const Eigen::VectorXd x_m = TransformPoints(R, Eigen::Vector3d::Zero(),
                                                model.rest_positions_m + 1e-3 * random.Vector(12));
    const Vector12d u_m = R_big.transpose() * x_m - model.rest_positions_m;
    Eigen::VectorXd force_N;
    CalcElasticForce(model, x_m, {R}, &force_N);
    const Vector12d force_slow_N = -R_big * K_e * u_m;
    EXPECT_LE((force_N - force_slow_N).norm(), kAssemblyRoundOff * K_e.norm() * u_m.norm());
    EXPECT_NEAR(CalcElasticEnergy(model, x_m, {R}), 0.5 * u_m.dot(K_e * u_m),
                kAssemblyRoundOff * K_e.norm() * u_m.squaredNorm());
  }
}

// MultiplySymmetric reads only the stored lower triangle; its product must equal the dense
// product with the full symmetric matrix, which is built independently of it by Eigen.
TEST(WarpedStiffness, ProductFromTheLowerTriangleEqualsTheFullProduct) {
  const Model model = MakeBlockModel();
  Random random(19);
  const Eigen::VectorXd x_m =
      TransformPoints(ArbitraryRotation(), Eigen::Vector3d::Zero(), model.rest_positions_m) +
      0.1 * kCell_m * random.Vector(model.num_dofs());
  std::vector<Eigen::Matrix3d> rotations;
  CalcElementRotations(model, x_m, ElasticityKind::kCorotational, &rotations);
  const StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(model, rotations, /*scale=*/1.0, &K);
  for (Eigen::Index col = 0; col < K.outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, col); it; ++it)
      ASSERT_GE(it.row(), it.col());  // only the lower triangle is stored
  const Eigen::VectorXd v = random.Vector(model.num_dofs());
  Eigen::VectorXd Kv;
  MultiplySymmetric(K, v, &Kv);
  const Eigen::VectorXd expected = AssembleDense(model, rotations) * v;
  EXPECT_LE((Kv - expected).norm(), kAssemblyRoundOff * expected.norm());
}

// A node in no tet would have no diagonal entry for its mass: refused with its index.
TEST(WarpedStiffness, ANodeInNoTetIsRefused) {
  TetMesh mesh;
  mesh.rest_positions_m.resize(3, 5);
  mesh.rest_positions_m << 0.0, 0.01, 0.0, 0.0, 0.05,  //
      0.0, 0.0, 0.01, 0.0, 0.05,                       //
      0.0, 0.0, 0.0, 0.01, 0.05;
  mesh.tets.resize(4, 1);
  mesh.tets << 0, 1, 2, 3;
  const Model model = MakeModel(mesh, MakeMaterial(), {});
  try {
    const StiffnessAssembler assembler(model);
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("node 4"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace hapsim::fem
