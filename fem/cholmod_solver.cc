#include "fem/cholmod_solver.h"

#include "fem/cg_solver.h"

namespace hapsim::fem {

SolveReport CholmodSolver::Solve(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b,
                                 double /*relative_tolerance*/, Eigen::VectorXd* x) {
  SolveReport report;
  report.iterations = 1;
  ++num_factorizations_;  // attempted: it costs the same whether or not A is definite
  if (!factor_.Factorize(A)) {
    report.relative_residual = 1.0;  // not positive definite: no solution
    return report;
  }
  return SolveWithFactor(A, b, x);
}

SolveReport CholmodSolver::SolveAgain(const Eigen::SparseMatrix<double>& A,
                                      const Eigen::VectorXd& b, double relative_tolerance,
                                      Eigen::VectorXd* x) {
  if (!factor_.is_factored()) return Solve(A, b, relative_tolerance, x);
  return SolveWithFactor(A, b, x);
}

SolveReport CholmodSolver::SolveWithFactor(const Eigen::SparseMatrix<double>& A,
                                           const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  SolveReport report;
  report.iterations = 1;
  factor_.Solve(b, x);
  // The residual costs one product with A; it shows what round-off leaves of the direct solve.
  const double b_norm = b.norm();
  if (b_norm > 0.0) {
    MultiplySymmetric(A, *x, &residual_);
    residual_ -= b;
    report.relative_residual = residual_.norm() / b_norm;
  }
  report.converged = true;
  return report;
}

}  // namespace hapsim::fem
