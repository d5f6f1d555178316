// A body of quadratic tets (issue 27): the mesh with its edge nodes, the curved boundary's
// sub-triangles, the model's mass, the assembled stiffness against a dense sum of the elements'
// own, the elastic force of a rigid motion, and a cantilever against beam theory, P1 beside P2.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

#include "fem/corotational.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/quadratic_tet.h"
#include "fem/stiffness_assembly.h"
#include "fem/time_stepper.h"
#include "tests/fem/static_solve.h"

namespace hapsim::fem {
namespace {

Material Rubber() {
  Material material;
  material.youngs_modulus_Pa = 1e7;
  material.poisson_ratio = 0.3;
  material.density_kg_m3 = 1000.0;
  return material;
}

TEST(MakeQuadraticMesh, AddsOneNodeAtTheMidpointOfEveryEdge) {
  const TetMesh linear = MakeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.03, 0.02, 0.01),
                                        Eigen::Vector3i(3, 2, 1));
  const TetMesh mesh = MakeQuadraticMesh(linear);
  // The edges counted independently: distinct sorted corner pairs over the tets.
  std::set<std::pair<int, int>> edges;
  for (int t = 0; t < linear.num_tets(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        edges.insert(std::minmax(linear.tets(a, t), linear.tets(b, t)));
  EXPECT_EQ(mesh.num_nodes(), linear.num_nodes() + static_cast<int>(edges.size()));
  EXPECT_EQ(mesh.tets, linear.tets);
  EXPECT_FALSE(FindRestMeshProblem(mesh).has_value());
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int k = 0; k < 6; ++k) {
      const Eigen::Vector3d midpoint =
          0.5 * (mesh.rest_positions_m.col(mesh.tets(kP2EdgeCorners[k][0], t)) +
                 mesh.rest_positions_m.col(mesh.tets(kP2EdgeCorners[k][1], t)));
      EXPECT_LT((mesh.rest_positions_m.col(mesh.edge_nodes(k, t)) - midpoint).norm(), 1e-15);
    }
}

// Volume enclosed by oriented triangles, by the divergence theorem.
double EnclosedVolume(const Matrix3Xd& x, const Matrix3Xi& triangles) {
  double volume = 0.0;
  for (Eigen::Index f = 0; f < triangles.cols(); ++f)
    volume +=
        x.col(triangles(0, f)).dot(x.col(triangles(1, f)).cross(x.col(triangles(2, f)))) / 6.0;
  return volume;
}

TEST(MakeQuadraticMesh, ItsBoundaryIsFourOutwardSubTrianglesAFace) {
  const TetMesh linear = MakeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(0.03, 0.02, 0.01),
                                        Eigen::Vector3i(3, 2, 1));
  const TetMesh mesh = MakeQuadraticMesh(linear);
  const Matrix3Xi faces = ExtractBoundarySurface(linear);
  const Matrix3Xi sub = ExtractBoundarySurface(mesh);
  EXPECT_EQ(sub.cols(), 4 * faces.cols());
  EXPECT_NEAR(EnclosedVolume(mesh.rest_positions_m, sub), 0.03 * 0.02 * 0.01, 1e-15);
  // Each sub-triangle is a quarter of its face's area and faces the same way.
  for (Eigen::Index f = 0; f < faces.cols(); ++f) {
    const auto normal = [](const Matrix3Xd& x, const Eigen::Vector3i& t) {
      return Eigen::Vector3d((x.col(t[1]) - x.col(t[0])).cross(x.col(t[2]) - x.col(t[0])));
    };
    const Eigen::Vector3d n = normal(linear.rest_positions_m, faces.col(f));
    for (int k = 0; k < 4; ++k)
      EXPECT_LT((4.0 * normal(mesh.rest_positions_m, sub.col(4 * f + k)) - n).norm(),
                1e-12 * n.norm());
  }
}

TEST(QuadraticModel, MassIsRhoVAndTheAssemblyIsTheSumOfTheElements) {
  const TetMesh mesh = MakeQuadraticMesh(MakeBoxTetMesh(
      Eigen::Vector3d::Zero(), Eigen::Vector3d(0.03, 0.02, 0.02), Eigen::Vector3i(3, 2, 2)));
  const Material material = Rubber();
  const Model model = MakeModel(mesh, material, {});
  EXPECT_NEAR(model.node_mass_kg.sum(), 1000.0 * 0.03 * 0.02 * 0.02, 1e-15);
  EXPECT_GT(model.node_mass_kg.minCoeff(), 0.0);
  // The assembler (lower triangle, blocks rotated) against a dense sum of each element's K_e
  // computed again by fem/quadratic_tet.h, under one rotation for all.
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(model, std::vector<Eigen::Matrix3d>(model.num_tets(), R), 2.0, &K);
  const Eigen::SparseMatrix<double> full = K.selfadjointView<Eigen::Lower>();
  const Eigen::MatrixXd assembled = Eigen::MatrixXd(full);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(model.num_dofs(), model.num_dofs());
  for (int t = 0; t < model.num_tets(); ++t) {
    P2Nodes X;
    for (int a = 0; a < kP2Nodes; ++a) X.col(a) = mesh.rest_positions_m.col(mesh.node(a, t));
    const QuadraticTetRest rest =
        MakeQuadraticTetRest(X, material.lame_mu_Pa(), material.lame_lambda_Pa(), 1000.0);
    for (int a = 0; a < kP2Nodes; ++a)
      for (int b = 0; b < kP2Nodes; ++b)
        dense.block<3, 3>(3 * mesh.node(a, t), 3 * mesh.node(b, t)) +=
            2.0 * R * rest.stiffness.block<3, 3>(3 * a, 3 * b) * R.transpose();
  }
  EXPECT_LT((assembled - dense).norm(), 1e-12 * dense.norm());
}

TEST(QuadraticModel, ARigidMotionHasNoElasticForceAndASmallStrainTheStiffnessOne) {
  const TetMesh mesh = MakeQuadraticMesh(MakeBoxTetMesh(
      Eigen::Vector3d::Zero(), Eigen::Vector3d(0.03, 0.02, 0.02), Eigen::Vector3i(3, 2, 2)));
  const Model model = MakeModel(mesh, Rubber(), {});
  const Eigen::Matrix3d Q =
      Eigen::AngleAxisd(2.0, Eigen::Vector3d(0.2, 1, -0.4).normalized()).toRotationMatrix();
  Eigen::VectorXd x(model.num_dofs());
  for (int n = 0; n < model.num_nodes(); ++n)
    x.segment<3>(3 * n) = Q * mesh.rest_positions_m.col(n) + Eigen::Vector3d(0.1, 0.2, -0.3);
  std::vector<Eigen::Matrix3d> rotations;
  CalcElementRotations(model, x, ElasticityKind::kCorotational, &rotations);
  Eigen::VectorXd force;
  CalcElasticForce(model, x, rotations, &force);
  // Against the force of a 1 % stretch along x, which the body does feel.
  Eigen::VectorXd stretched = model.rest_positions_m;
  for (int n = 0; n < model.num_nodes(); ++n) stretched[3 * n] *= 1.01;
  const std::vector<Eigen::Matrix3d> identity(model.num_tets(), Eigen::Matrix3d::Identity());
  Eigen::VectorXd felt;
  CalcElasticForce(model, stretched, identity, &felt);
  EXPECT_LT(force.norm(), 1e-10 * felt.norm());
  // With R = I the force is −K (x − X): the assembled K, a second path.
  const StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(model, identity, 1.0, &K);
  const Eigen::VectorXd expected =
      -(K.selfadjointView<Eigen::Lower>() * (stretched - model.rest_positions_m));
  EXPECT_LT((felt - expected).norm(), 1e-12 * expected.norm());
  EXPECT_NEAR(CalcElasticEnergy(model, stretched, identity),
              -0.5 * (stretched - model.rest_positions_m).dot(expected), 1e-12 * felt.norm());
}

// The scene cantilever's beam (E 1e7 Pa, ν 0.3) against beam theory (3.717 mm).
double CantileverTipDeflection(const Eigen::Vector3i& cells, bool quadratic) {
  return test::SolveCantileverTipDeflection(test::MakeCantilever(cells, Rubber(), quadratic));
}

TEST(QuadraticModel, ACantileverConvergesWhereLinearTetsLock) {
  const double reference = test::CalcCantileverBeamTheory_m(Rubber());
  double p2_errors[2], p1_errors[2];
  const Eigen::Vector3i meshes[2] = {{10, 2, 2}, {20, 2, 2}};
  for (int k = 0; k < 2; ++k) {
    p1_errors[k] = std::abs(CantileverTipDeflection(meshes[k], false) / reference - 1.0);
    p2_errors[k] = std::abs(CantileverTipDeflection(meshes[k], true) / reference - 1.0);
    std::printf("cantilever %dx%dx%d cells: P1 error %.1f %%, P2 error %.2f %%\n", meshes[k][0],
                meshes[k][1], meshes[k][2], 100 * p1_errors[k], 100 * p2_errors[k]);
  }
  // Linear tets lock in bending: tens of per cent off on these meshes. Quadratic ones are within
  // the 3 % on both, and their error is a fraction of the linear tets'.
  EXPECT_GT(p1_errors[1], 0.2);
  EXPECT_LT(p2_errors[0], 0.03);
  EXPECT_LT(p2_errors[1], 0.03);
  EXPECT_LT(p2_errors[1], p1_errors[1] / 10.0);
}

}  // namespace
}  // namespace hapsim::fem
