#pragma once
// Static solves for the element tests (quadratic_model_test): K u = f at rest,
// and the scene cantilever's beam (0.5 m, 5 × 5 cm) clamped at x = 0 under a tenth of its weight
// with beam theory's answer for it.

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cmath>
#include <vector>

#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/stiffness_assembly.h"
#include "fem/time_stepper.h"

namespace hapsim::fem::test {

// The beam's lattice (cells along x, y, z), quadratic or linear, clamped at x = 0.
inline Model MakeCantilever(const Eigen::Vector3i& cells, const Material& material,
                            bool quadratic) {
  TetMesh mesh =
      MakeBoxTetMesh(Eigen::Vector3d(0, -0.025, -0.025), Eigen::Vector3d(0.5, 0.025, 0.025), cells);
  if (quadratic) mesh = MakeQuadraticMesh(mesh);
  const std::vector<int> clamped = FindNodesInBox(mesh, Eigen::Vector3d(-0.001, -0.03, -0.03),
                                                  Eigen::Vector3d(0.001, 0.03, 0.03), 0.0);
  return MakeModel(mesh, material, clamped);
}

// u solving K u = f on the free dofs (K at rest, rotations I), 0 on the fixed ones.
inline Eigen::VectorXd SolveStaticDisplacement(const Model& model, const Eigen::VectorXd& f) {
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
  Eigen::VectorXd f_free(free.size());
  for (size_t k = 0; k < free.size(); ++k) f_free[k] = f[free[k]];
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(K_free);
  const Eigen::VectorXd u_free = solver.solve(f_free);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(model.num_dofs());
  for (size_t k = 0; k < free.size(); ++k) u[free[k]] = u_free[k];
  return u;
}

// The node at p_m (rest), or −1.
inline int FindNodeAt(const Model& model, const Eigen::Vector3d& p_m) {
  for (int n = 0; n < model.num_nodes(); ++n)
    if ((model.mesh.rest_positions_m.col(n) - p_m).norm() < 1e-9) return n;
  return -1;
}

// The tip centre's static deflection (m, down) under a tenth of gravity on the lumped masses (as
// the stepper loads them). The tip's centre (0.5, 0, 0) must be a node (even cells across).
inline double SolveCantileverTipDeflection(const Model& model) {
  const Eigen::VectorXd u =
      SolveStaticDisplacement(model, CalcGravityForce(model, Eigen::Vector3d(0, 0, -0.981)));
  const int tip = FindNodeAt(model, Eigen::Vector3d(0.5, 0, 0));
  if (tip < 0) ADD_FAILURE() << "no node at the tip's centre";
  return tip < 0 ? 0.0 : -u[3 * tip + 2];
}

// Beam theory for it: q L⁴/(8 E I) + q L²/(2 κ G A), κ = 10(1 + ν)/(12 + 11ν), q the tenth of the
// weight per length (scripts/bench/beam_theory.py).
inline double CalcCantileverBeamTheory_m(const Material& material) {
  const double E = material.youngs_modulus_Pa, nu = material.poisson_ratio, h = 0.05, L = 0.5;
  const double q = material.density_kg_m3 * 0.981 * h * h;
  const double I = h * h * h * h / 12.0, G = E / (2.0 * (1.0 + nu));
  const double kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu);
  return q * std::pow(L, 4) / (8.0 * E * I) + q * L * L / (2.0 * kappa * G * h * h);
}

}  // namespace hapsim::fem::test
