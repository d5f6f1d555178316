#pragma once
// Small helpers shared by the FEM validation tests: a static equilibrium solver, forces and
// energies at the current rotations, rigid transforms, deterministic random numbers, the unit
// quadratic tet.
// Header-only; nothing here is under test.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "fem/cholmod_factor.h"
#include "fem/corotational.h"
#include "fem/fem_options.h"
#include "fem/model.h"
#include "fem/stiffness_assembly.h"
#include "fem/tet_mesh.h"

namespace hapsim::fem::test {

struct StaticSolveReport {
  int iterations = 0;              // quasi-Newton iterations (one factorisation each)
  double residual_norm_N = 0.0;    // ‖f_ext + f_el(x)‖ over the free dofs at exit
  double round_off_floor_N = 0.0;  // kForceRoundOff · max|K_ii| · ‖x‖ at exit
  bool converged = false;
};

// The elastic force is evaluated from absolute positions through F = Σ x_i b_iᵀ, so it carries
// an absolute round-off of a few ε_mach · ‖K‖ · ‖x‖ that no solver can remove. For a stiff,
// slender body (element forces ≫ net nodal loads) this floor lies above 1e-10 ‖f_ext‖; there
// the static solve is converged once the residual reaches it (≈ 5 ε_mach, max|K_ii| for ‖K‖).
constexpr double kForceRoundOff = 1e-15;

// Replaces the rows and columns of fixed dofs of K (pattern of a StiffnessAssembler) by those of
// the identity, so that a solve leaves those dofs unchanged.
inline void ApplyFixedDofs(const Model& model, Eigen::SparseMatrix<double>* K) {
  for (Eigen::Index col = 0; col < K->outerSize(); ++col)
    for (Eigen::SparseMatrix<double>::InnerIterator it(*K, col); it; ++it)
      if (model.dof_is_fixed[it.row()] || model.dof_is_fixed[it.col()])
        it.valueRef() = it.row() == it.col() ? 1.0 : 0.0;
}

// Static equilibrium f_ext + f_el(x) = 0 with the fixed dofs held at their value in *x_m.
// Quasi-Newton: each iteration solves K Δx = f_ext + f_el(x) with the warped stiffness
// K = Σ R_e K_e R_eᵀ at the current rotations (exact Newton for kLinear; for kCorotational it omits
// ∂R/∂x, so convergence is linear with a rate of the order of the strain). Stops at
// ‖residual‖ ≤ max(relative_tolerance · ‖f_ext‖, round-off floor) over the free dofs.
inline StaticSolveReport SolveStaticEquilibrium(const Model& model, ElasticityKind kind,
                                                const Eigen::VectorXd& external_force_N,
                                                Eigen::VectorXd* x_m,
                                                double relative_tolerance = 1e-10,
                                                int max_iterations = 30) {
  const StiffnessAssembler assembler(model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  CholmodFactor factor;
  std::vector<Eigen::Matrix3d> rotations;
  Eigen::VectorXd residual_N, step_m;
  Eigen::VectorXd free_external_N = external_force_N;
  for (int i = 0; i < model.num_dofs(); ++i)
    if (model.dof_is_fixed[i]) free_external_N[i] = 0.0;
  const double target_N = relative_tolerance * free_external_N.norm();
  StaticSolveReport report;
  for (;; ++report.iterations) {
    CalcElementRotations(model, *x_m, kind, &rotations);
    CalcElasticForce(model, *x_m, rotations, &residual_N);
    residual_N += external_force_N;
    for (int i = 0; i < model.num_dofs(); ++i)
      if (model.dof_is_fixed[i]) residual_N[i] = 0.0;
    assembler.Assemble(model, rotations, /*scale=*/1.0, &K);
    double max_diagonal = 0.0;
    for (int index : assembler.diagonal_value_index())
      max_diagonal = std::max(max_diagonal, std::abs(K.valuePtr()[index]));
    report.round_off_floor_N = kForceRoundOff * max_diagonal * x_m->norm();
    report.residual_norm_N = residual_N.norm();
    if (!std::isfinite(report.residual_norm_N)) return report;
    if (report.residual_norm_N <= std::max(target_N, report.round_off_floor_N)) {
      report.converged = true;
      return report;
    }
    if (report.iterations == max_iterations) return report;
    ApplyFixedDofs(model, &K);
    if (!factor.Factorize(K)) throw std::runtime_error("stiffness not positive definite");
    factor.Solve(residual_N, &step_m);
    *x_m += step_m;
  }
}

// Total elastic energy with the rotations of the current positions, J.
inline double CalcElasticEnergyAt(const Model& model, const Eigen::VectorXd& x_m,
                                  ElasticityKind kind = ElasticityKind::kCorotational) {
  std::vector<Eigen::Matrix3d> rotations;
  CalcElementRotations(model, x_m, kind, &rotations);
  return CalcElasticEnergy(model, x_m, rotations);
}

// Elastic force with the rotations of x_m (the true corotational force field f(x)).
inline Eigen::VectorXd CalcElasticForceAt(const Model& model, const Eigen::VectorXd& x_m,
                                          ElasticityKind kind) {
  std::vector<Eigen::Matrix3d> rotations;
  CalcElementRotations(model, x_m, kind, &rotations);
  Eigen::VectorXd force_N;
  CalcElasticForce(model, x_m, rotations, &force_N);
  return force_N;
}

// Applies x ← R x + t to every node of a stacked 3N vector.
inline Eigen::VectorXd TransformPoints(const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                                       const Eigen::VectorXd& x_m) {
  Eigen::VectorXd y_m(x_m.size());
  for (Eigen::Index n = 0; n < x_m.size() / 3; ++n)
    y_m.segment<3>(3 * n) = R * x_m.segment<3>(3 * n) + t;
  return y_m;
}

// Deterministic uniform random numbers in [-1, 1].
class Random {
 public:
  explicit Random(unsigned seed) : engine_(seed) {}
  double Uniform() { return distribution_(engine_); }
  Eigen::VectorXd Vector(Eigen::Index n) {
    Eigen::VectorXd v(n);
    for (Eigen::Index i = 0; i < n; ++i) v[i] = Uniform();
    return v;
  }
  Eigen::Matrix3d Matrix3() {
    Eigen::Matrix3d A;
    for (int i = 0; i < 9; ++i) A.data()[i] = Uniform();
    return A;
  }
  // A rotation drawn from a random axis and angle in [-π, π].
  Eigen::Matrix3d Rotation() {
    Eigen::Vector3d axis(Uniform(), Uniform(), Uniform());
    if (axis.norm() < 1e-3) axis = Eigen::Vector3d::UnitX();
    return Eigen::AngleAxisd(M_PI * Uniform(), axis.normalized()).toRotationMatrix();
  }

 private:
  std::mt19937 engine_;
  std::uniform_real_distribution<double> distribution_{-1.0, 1.0};
};

// Zeroes the entries of the fixed dofs of a 3N vector.
inline Eigen::VectorXd ZeroFixedDofs(const Model& model, Eigen::VectorXd v) {
  for (int i = 0; i < model.num_dofs(); ++i)
    if (model.dof_is_fixed[i]) v[i] = 0.0;
  return v;
}

// One quadratic tet, corners at the origin and the unit axes, its edge nodes at the midpoints.
inline TetMesh MakeUnitQuadraticTet() {
  TetMesh linear;
  linear.rest_positions_m.resize(3, 4);
  linear.rest_positions_m << 0, 1, 0, 0,  //
      0, 0, 1, 0,                         //
      0, 0, 0, 1;
  linear.tets.resize(4, 1);
  linear.tets << 0, 1, 2, 3;
  return MakeQuadraticMesh(linear);
}

}  // namespace hapsim::fem::test
