#pragma once
// Solvers for the SPD system of the implicit step, A Δv = Δt F̃ (DESIGN.md §2), chosen once per
// scene through this small interface; the inner loops run on concrete types.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <memory>

#include "fem/cholmod_factor.h"
#include "fem/fem_options.h"

namespace hapsim::fem {

struct SolveReport {
  int iterations = 0;              // CG iterations; 1 for a direct solve
  double relative_residual = 0.0;  // ‖b − A x‖ / ‖b‖ (0 when b = 0)
  bool converged = false;          // residual within tolerance (direct: factorisation succeeded)
};

class LinearSolver {
 public:
  virtual ~LinearSolver() = default;
  // Solves A x = b for symmetric positive definite A, lower triangle stored (StiffnessAssembler).
  // On entry *x is the initial guess (CG warm start; ignored by direct solvers). CG stops at
  // ‖b − A x‖ ≤ relative_tolerance · ‖b‖ (the step passes SolverOptions::relative_tolerance; a
  // direct solver ignores it). The sparsity pattern of A must stay the same between calls (it is
  // analysed once).
  virtual SolveReport Solve(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b,
                            double relative_tolerance, Eigen::VectorXd* x) = 0;
  // Solve with the A of the last Solve, its values unchanged since: a direct solver reuses the
  // factor it made then (the visual frame's contact correction after the free step).
  virtual SolveReport SolveAgain(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b,
                                 double relative_tolerance, Eigen::VectorXd* x) {
    return Solve(A, b, relative_tolerance, x);
  }

  // The Cholesky factor the solver holds, or nullptr: CholmodSolver's is of the last A, CG with
  // a lagged Cholesky preconditioner holds one of an earlier A. Contact compliance uses it.
  virtual CholmodFactor* factor() { return nullptr; }

  // The pattern A will have: a solver that factors does its ordering and symbolic analysis now
  // (TimeStepper calls it at construction, where the pattern is built) instead of in the first
  // Solve.
  virtual void AnalyzePattern(const Eigen::SparseMatrix<double>& /*A*/) {}

  // Numeric sparse Cholesky factorisations done so far: one per Solve for CholmodSolver, those
  // of the lagged preconditioner for CG (0 with block Jacobi).
  virtual int num_factorizations() const = 0;
};

std::unique_ptr<LinearSolver> MakeLinearSolver(const SolverOptions& options);

}  // namespace hapsim::fem
