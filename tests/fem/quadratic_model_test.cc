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

// The scene cantilever's beam (0.5 m, 5 × 5 cm, E 1e7 Pa, ν 0.3) clamped at x = 0 under a tenth of
// its weight, solved statically (K u = f, K at rest): the tip's deflection against beam theory,
// q L⁴/(8 E I) + q L²/(2 κ G A) with κ = 10(1 + ν)/(12 + 11ν) (scripts/bench/beam_theory.py:
// 3.717 mm). The gravity load is the lumped masses' (as the stepper's).
double CantileverTipDeflection(const Eigen::Vector3i& cells, bool quadratic) {
  TetMesh mesh =
      MakeBoxTetMesh(Eigen::Vector3d(0, -0.025, -0.025), Eigen::Vector3d(0.5, 0.025, 0.025), cells);
  if (quadratic) mesh = MakeQuadraticMesh(mesh);
  const std::vector<int> clamped = FindNodesInBox(mesh, Eigen::Vector3d(-0.001, -0.03, -0.03),
                                                  Eigen::Vector3d(0.001, 0.03, 0.03), 0.0);
  const Model model = MakeModel(mesh, Rubber(), clamped);
  const StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  assembler.Assemble(
      model, std::vector<Eigen::Matrix3d>(model.num_tets(), Eigen::Matrix3d::Identity()), 1.0, &K);
  const Eigen::SparseMatrix<double> full = K.selfadjointView<Eigen::Lower>();
  std::vector<int> free;
  for (int i = 0; i < model.num_dofs(); ++i)
    if (!model.dof_is_fixed[i]) free.push_back(i);
  std::vector<int> index_of(model.num_dofs(), -1);
  for (size_t k = 0; k < free.size(); ++k) index_of[free[k]] = static_cast<int>(k);
  std::vector<Eigen::Triplet<double>> entries;
  for (int c = 0; c < full.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(full, c); it; ++it)
      if (index_of[it.row()] >= 0 && index_of[c] >= 0)
        entries.emplace_back(index_of[it.row()], index_of[c], it.value());
  Eigen::SparseMatrix<double> K_free(free.size(), free.size());
  K_free.setFromTriplets(entries.begin(), entries.end());
  const Eigen::VectorXd f = CalcGravityForce(model, Eigen::Vector3d(0, 0, -0.981));
  Eigen::VectorXd f_free(free.size());
  for (size_t k = 0; k < free.size(); ++k) f_free[k] = f[free[k]];
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(K_free);
  const Eigen::VectorXd u_free = solver.solve(f_free);
  // The tip's centre (0.5, 0, 0) is a node of both meshes (even cell counts across).
  for (int n = 0; n < mesh.num_nodes(); ++n)
    if ((mesh.rest_positions_m.col(n) - Eigen::Vector3d(0.5, 0, 0)).norm() < 1e-9)
      return -u_free[index_of[3 * n + 2]];
  ADD_FAILURE() << "no node at the tip's centre";
  return 0.0;
}

TEST(QuadraticModel, ACantileverConvergesWhereLinearTetsLock) {
  const double nu = 0.3, E = 1e7, h = 0.05, L = 0.5, q = 1000.0 * 0.981 * h * h;
  const double I = h * h * h * h / 12.0, G = E / (2.0 * (1.0 + nu));
  const double kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
  const double reference =
      q * std::pow(L, 4) / (8.0 * E * I) + q * L * L / (2.0 * kappa * G * h * h);
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
