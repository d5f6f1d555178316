// Average nodal pressure on linear tets (fem/nodal_pressure.h), against independent values:
//  - the patch test: a uniform strain (any affine map of the nodes, rotated too) gives the plain
//    tets' force exactly (every node's averaged strain is the tets' own);
//  - a rigid motion gives no force and no energy;
//  - its stiffness (the assembler's K, wider pattern) against central differences of its force
//    with the rotations held, and its force against differences of its energy;
//  - locking reduced: a block sagging under its weight at ν 0.49, against quadratic tets twice as
//    fine (a second method that does not lock).
#include "fem/nodal_pressure.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <vector>

#include "fem/corotational.h"
#include "fem/lattice_mesher.h"
#include "fem/stiffness_assembly.h"
#include "tests/fem/static_solve.h"

namespace hapsim::fem {
namespace {

Material Tissue(double poisson_ratio) {
  Material material;
  material.youngs_modulus_Pa = 1e4;
  material.poisson_ratio = poisson_ratio;
  material.density_kg_m3 = 1000.0;
  return material;
}

// A 3 × 2 × 2 cm block of 3 × 2 × 2 cells; with nodal pressure or without.
Model MakeBlockModel(bool nodal_pressure, double poisson_ratio = 0.49) {
  Model model = MakeModel(
      MakeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.03, 0.02, 0.02), {3, 2, 2}),
      Tissue(poisson_ratio), {});
  if (nodal_pressure) EnableNodalPressure(&model);
  return model;
}

Eigen::VectorXd Mapped(const Model& model, const Eigen::Matrix3d& A, const Eigen::Vector3d& t) {
  Eigen::VectorXd x_m(model.num_dofs());
  for (int n = 0; n < model.num_nodes(); ++n)
    x_m.segment<3>(3 * n) = A * model.mesh.rest_positions_m.col(n) + t;
  return x_m;
}

Eigen::VectorXd Force(const Model& model, const Eigen::VectorXd& x_m,
                      const std::vector<Eigen::Matrix3d>& rotations) {
  Eigen::VectorXd force_N;
  CalcElasticForce(model, x_m, rotations, &force_N);
  return force_N;
}

TEST(NodalPressure, NodeSharesAddUpToTheVolume) {
  const Model model = MakeBlockModel(true);
  EXPECT_NEAR(model.nodal_pressure.node_volume_m3.sum(), 0.03 * 0.02 * 0.02, 1e-18);
  const Material tissue = Tissue(0.49);
  const double bulk_Pa = tissue.lame_lambda_Pa() + 2.0 / 3.0 * tissue.lame_mu_Pa();
  EXPECT_NEAR(model.nodal_pressure.node_bulk_Pa.maxCoeff(), bulk_Pa, 1e-9 * bulk_Pa);
  EXPECT_NEAR(model.nodal_pressure.node_bulk_Pa.minCoeff(), bulk_Pa, 1e-9 * bulk_Pa);
}

TEST(NodalPressure, AUniformStrainGivesThePlainTetsForce) {
  const Model plain = MakeBlockModel(false), nodal = MakeBlockModel(true);
  Eigen::Matrix3d stretch;
  stretch << 1.02, 0.005, -0.01, 0.005, 0.97, 0.004, -0.01, 0.004, 1.03;
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, -1).normalized()).toRotationMatrix();
  for (const Eigen::Matrix3d& A : {Eigen::Matrix3d(stretch), Eigen::Matrix3d(turn * stretch)}) {
    const Eigen::VectorXd x_m = Mapped(plain, A, Eigen::Vector3d(0.01, -0.02, 0.005));
    std::vector<Eigen::Matrix3d> rotations;
    CalcElementRotations(plain, x_m, ElasticityKind::kCorotational, &rotations);
    const Eigen::VectorXd f_plain = Force(plain, x_m, rotations);
    const Eigen::VectorXd f_nodal = Force(nodal, x_m, rotations);
    ASSERT_GT(f_plain.norm(), 1.0);  // the volume changes: a force worth testing
    EXPECT_LT((f_nodal - f_plain).norm(), 1e-10 * f_plain.norm());
    EXPECT_NEAR(CalcElasticEnergy(nodal, x_m, rotations), CalcElasticEnergy(plain, x_m, rotations),
                1e-10 * CalcElasticEnergy(plain, x_m, rotations));
  }
}

TEST(NodalPressure, ARigidMotionGivesNoForce) {
  const Model nodal = MakeBlockModel(true);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(-1, 0.5, 2).normalized()).toRotationMatrix();
  const Eigen::VectorXd x_m = Mapped(nodal, turn, Eigen::Vector3d(0.2, 0.1, -0.3));
  std::vector<Eigen::Matrix3d> rotations;
  CalcElementRotations(nodal, x_m, ElasticityKind::kCorotational, &rotations);
  // The scale a 1 % strain would give: E · strain · area.
  EXPECT_LT(Force(nodal, x_m, rotations).cwiseAbs().maxCoeff(), 1e-9 * 1e4 * 0.01 * 1e-4);
  EXPECT_LT(std::abs(CalcElasticEnergy(nodal, x_m, rotations)), 1e-20);
}

// The rotations of a deformed state held fixed: f is then linear in x, so central differences are
// exact to round-off, and f = −∂E/∂x.
TEST(NodalPressure, StiffnessAndForceAreTheEnergysDerivatives) {
  const Model nodal = MakeBlockModel(true);
  Eigen::VectorXd x_m = nodal.rest_positions_m;
  for (int i = 0; i < nodal.num_dofs(); ++i) x_m[i] += 1e-3 * std::sin(1.7 * i + 0.3);
  std::vector<Eigen::Matrix3d> rotations;
  CalcElementRotations(nodal, x_m, ElasticityKind::kCorotational, &rotations);
  const StiffnessAssembler assembler(nodal);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(nodal, rotations, 1.0, &K);
  const Eigen::SparseMatrix<double> K_symmetric = K.selfadjointView<Eigen::Lower>();
  const Eigen::MatrixXd K_full(K_symmetric);
  const double h = 1e-5;
  const Eigen::VectorXd f = Force(nodal, x_m, rotations);
  double worst = 0.0;
  for (int i = 0; i < nodal.num_dofs(); ++i) {
    Eigen::VectorXd plus = x_m, minus = x_m;
    plus[i] += h;
    minus[i] -= h;
    const Eigen::VectorXd column =
        -(Force(nodal, plus, rotations) - Force(nodal, minus, rotations)) / (2.0 * h);
    worst = std::max(worst, (K_full.col(i) - column).cwiseAbs().maxCoeff());
    const double dE =
        (CalcElasticEnergy(nodal, plus, rotations) - CalcElasticEnergy(nodal, minus, rotations)) /
        (2.0 * h);
    EXPECT_NEAR(dE, -f[i], 1e-6 * f.cwiseAbs().maxCoeff()) << i;
  }
  EXPECT_LT(worst, 1e-6 * K_full.cwiseAbs().maxCoeff());
  // The volumetric part reaches nodes two tets apart: a wider pattern than the plain tets'.
  EXPECT_GT(K.nonZeros(), StiffnessAssembler(MakeBlockModel(false)).MakeMatrix().nonZeros());
}

// Volumetric locking, where it shows: a soft block (4 × 4 × 2 cm, its base fixed, sides free)
// sagging under its weight at ν 0.49, a compression the material can only take by bulging
// sideways. Its top centre's static deflection against a second method, quadratic tets twice as
// fine (which do not lock; tests/fem/quadratic_model_test.cc): linear tets are far too stiff,
// and average nodal pressure on the same linear mesh takes most of that away.
double SagOfBlock(const Eigen::Vector3i& cells, bool quadratic, bool nodal_pressure) {
  TetMesh mesh =
      MakeBoxTetMesh(Eigen::Vector3d(-0.02, -0.02, 0.0), Eigen::Vector3d(0.02, 0.02, 0.02), cells);
  if (quadratic) mesh = MakeQuadraticMesh(mesh);
  const std::vector<int> base = FindNodesInBox(mesh, Eigen::Vector3d(-0.03, -0.03, -1e-4),
                                               Eigen::Vector3d(0.03, 0.03, 1e-4), 0.0);
  Model model = MakeModel(mesh, Tissue(0.49), base);
  if (nodal_pressure) EnableNodalPressure(&model);
  const Eigen::VectorXd u =
      test::SolveStaticDisplacement(model, CalcGravityForce(model, Eigen::Vector3d(0, 0, -9.81)));
  const int top = test::FindNodeAt(model, Eigen::Vector3d(0, 0, 0.02));
  EXPECT_GE(top, 0);
  return top < 0 ? 0.0 : -u[3 * top + 2];
}

TEST(NodalPressure, TakesMostOfTheLockingOutOfASaggingBlock) {
  const Eigen::Vector3i cells(8, 8, 4);
  const double reference = SagOfBlock(2 * cells, true, false);
  const double plain = SagOfBlock(cells, false, false) / reference - 1.0;
  const double nodal = SagOfBlock(cells, false, true) / reference - 1.0;
  const double quadratic = SagOfBlock(cells, true, false) / reference - 1.0;
  std::printf(
      "sag at nu 0.49 against P2 %dx%dx%d (%.4g mm): P1 %.1f %%, P1 nodal pressure %.1f %%, "
      "P2 %.1f %%\n",
      2 * cells[0], 2 * cells[1], 2 * cells[2], 1e3 * reference, 100 * plain, 100 * nodal,
      100 * quadratic);
  EXPECT_LT(plain, -0.2);  // linear tets lock: a fifth too stiff, or more
  EXPECT_LT(std::abs(nodal), 0.6 * std::abs(plain));  // nodal pressure: measured 0.49 of it
}

}  // namespace
}  // namespace hapsim::fem
