#pragma once
// Preconditioned conjugate gradients, warm-started from the caller's x; stops at
// ‖b − Ax‖ ≤ tol ‖b‖ or after max_iterations. Preconditioner: a lagged Cholesky factor of an
// earlier A (refreshed when CG slows down) or 3×3 block Jacobi (see PreconditionerKind).

#include <vector>

#include "fem/cholmod_factor.h"
#include "fem/linear_solver.h"

namespace hapsim::fem {

class ConjugateGradientSolver final : public LinearSolver {
 public:
  explicit ConjugateGradientSolver(const SolverOptions& options) : options_(options) {
    factor_.KeepCopy(options.factor_precision);
  }
  SolveReport Solve(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b,
                    double relative_tolerance, Eigen::VectorXd* x) override;

  int num_factorizations() const override { return num_factorizations_; }
  CholmodFactor* factor() override { return factor_.is_factored() ? &factor_ : nullptr; }
  void AnalyzePattern(const Eigen::SparseMatrix<double>& A) override {
    if (options_.preconditioner == PreconditionerKind::kLaggedCholesky) factor_.Analyze(A);
  }

 private:
  void PreparePreconditioner(const Eigen::SparseMatrix<double>& A);
  void ApplyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd* z);

  SolverOptions options_;
  bool use_factor_ = false;
  bool factored_this_solve_ = false;
  int baseline_iterations_ = 0;  // iterations of the first solve after the last factorisation
  int excess_iterations_ = 0;    // Σ (iterations − baseline) since then
  int num_factorizations_ = 0;
  CholmodFactor factor_;
  std::vector<Eigen::Matrix3d> block_inverse_;  // block Jacobi: one per node
  Eigen::VectorXd r_, z_, p_, Ap_;              // scratch, sized on first use
};

// y = A x for symmetric A of which the lower triangle is stored (column-major, rows sorted, as
// StiffnessAssembler builds it): each off-diagonal entry a_ij adds to y_i and, as a_ji, to y_j.
void MultiplySymmetric(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& x,
                       Eigen::VectorXd* y);

}  // namespace hapsim::fem
