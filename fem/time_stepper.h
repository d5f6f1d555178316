#pragma once
// One time step of the deformable body (DESIGN.md §2). Reads the Model, updates the State; all
// scratch lives in the stepper, so steps after the first allocate nothing of size N.
//
// Linearised implicit backward Euler (one linear solve per step; Baraff & Witkin 1998):
//   A Δv = Δt F̃,   A = M + Δt D + Δt² K,   D = αM + βK,
//   F̃ = f_ext + f_el(x) − D v − Δt K v,      then v ← v + Δv,  x ← x + Δt v,
// with K the warped stiffness Σ R_e K_e R_eᵀ and f_el the corotational elastic force.
// Symplectic (explicit) Euler, v ← v + Δt M⁻¹ (f_ext + f_el − D v), x ← x + Δt v, is kept only to
// show where it fails: it is stable only for Δt below about 2/ω_max.
// Fixed dofs keep v = 0: their rows and columns of A are replaced by the identity.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>
#include <vector>

#include "fem/fem_options.h"
#include "fem/linear_solver.h"
#include "fem/model.h"
#include "fem/state.h"
#include "fem/stiffness_assembly.h"

namespace hapsim::fem {

// Wall time of each stage of one step, seconds, and what the solver reported.
struct StepStats {
  double rotations_s = 0.0;  // polar decompositions
  double assembly_s = 0.0;   // elastic forces, warped stiffness, right-hand side
  double solve_s = 0.0;      // linear solve
  double total_s = 0.0;
  SolveReport solve;
};

class TimeStepper {
 public:
  // `model` must outlive the stepper. external_force_N (3N) is constant (gravity, loads).
  TimeStepper(const Model& model, const FemOptions& options, double dt_s,
              Eigen::VectorXd external_force_N);

  // One whole step without contact: CalcFreeVelocityChange, then Advance.
  StepStats Step(State* state);

  // The stages of a step, for the visual frame, which adds contact impulses in between:
  // Δv_free of the collision-free update (implicit: assembles A and solves A Δv = Δt F̃).
  StepStats CalcFreeVelocityChange(const State& state, Eigen::VectorXd* dv_m_s);
  // x = A⁻¹ rhs with the A of the last CalcFreeVelocityChange (implicit integrator only); *x is
  // the initial guess for CG, which stops at relative_tolerance or the scene's solver tolerance,
  // whichever is looser (0: the solver's).
  SolveReport SolveWithSystemMatrix(const Eigen::VectorXd& rhs, double relative_tolerance,
                                    Eigen::VectorXd* x);
  // J A⁻¹ Jᵀ (rows x rows) with the solver's Cholesky factor: exact for CHOLMOD; for CG with a
  // lagged Cholesky preconditioner, the factor of an earlier A (an approximation of the same
  // order as the preconditioner's error). Throws std::logic_error for block Jacobi or explicit.
  Eigen::MatrixXd CalcCompliance(const Eigen::SparseMatrix<double>& J);
  // v ← v + Δv (fixed dofs kept at 0), x ← x + Δt v.
  void Advance(const Eigen::VectorXd& dv_m_s, State* state) const;

  double dt_s() const { return dt_s_; }
  // Whether some object of the body (Model::object_first_nodes; the body if one) has no fixed
  // dof: it rests on others or floats, and nothing but its own dynamics holds it.
  bool has_free_object() const { return has_free_object_; }
  const Eigen::VectorXd& external_force_N() const { return external_force_N_; }
  // Element rotations of the last step (at the positions it started from).
  const std::vector<Eigen::Matrix3d>& rotations() const { return rotations_; }
  const LinearSolver* solver() const { return solver_.get(); }
  // A = M + Δt D + Δt² K of the last CalcFreeVelocityChange (identity rows/columns at fixed dofs);
  // its lower triangle, as K is stored (fem/stiffness_assembly.h). Implicit integrator only: the
  // explicit step assembles no matrix.
  const Eigen::SparseMatrix<double>& system_matrix() const { return system_; }
  // The same A at rest (every element rotation the identity): the matrix whose inverse the
  // warped contact compliance precomputes (fem/warped_compliance.h).
  Eigen::SparseMatrix<double> MakeRestSystemMatrix() const;

 private:
  StepStats CalcImplicitVelocityChange(const State& state, Eigen::VectorXd* dv_m_s);
  StepStats CalcExplicitVelocityChange(const State& state, Eigen::VectorXd* dv_m_s);
  // Δt β + Δt², the factor of K in A.
  double StiffnessScale() const;
  // (Δt β + Δt²) K → A = (1 + Δt α) M + (Δt β + Δt²) K in place, with identity rows and columns
  // at fixed dofs.
  void AddMassAndFixedDofs(Eigen::SparseMatrix<double>* A) const;

  const Model& model_;
  FemOptions options_;
  double dt_s_;
  Eigen::VectorXd external_force_N_;
  StiffnessAssembler assembler_;
  std::unique_ptr<LinearSolver> solver_;
  std::vector<int> fixed_offdiagonal_value_index_;  // entries in a fixed row or column
  std::vector<int> fixed_dofs_;
  bool has_free_object_ = false;
  // Scratch.
  std::vector<Eigen::Matrix3d> rotations_;
  Eigen::SparseMatrix<double> system_;  // (Δt β + Δt²) K, then A in place (implicit only)
  Eigen::VectorXd shifted_x_m_, elastic_force_N_, rhs_, delta_v_m_s_, scratch_rhs_;
};

// Gravity on the lumped masses: f = m_n g for every node (3N, N).
Eigen::VectorXd CalcGravityForce(const Model& model, const Eigen::Vector3d& gravity_m_s2);

// Kinetic energy ½ vᵀ M v, J.
double CalcKineticEnergy(const Model& model, const State& state);

}  // namespace hapsim::fem
