#include "fem/cg_solver.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cassert>
#include <cmath>

namespace hapsim::fem {

void MultiplySymmetric(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& x,
                       Eigen::VectorXd* y) {
  const int* outer = A.outerIndexPtr();
  const int* rows = A.innerIndexPtr();
  const double* values = A.valuePtr();
  y->setZero(A.rows());
  double* out = y->data();
  const double* in = x.data();
  for (Eigen::Index j = 0; j < A.cols(); ++j) {
    int k = outer[j];
    const int end = outer[j + 1];
    // Full storage would count every off-diagonal entry twice.
    assert((k == end || rows[k] >= j) && "MultiplySymmetric needs the lower triangle only");
    const double x_j = in[j];
    double sum = 0.0;
    if (k < end && rows[k] == j) sum = values[k++] * x_j;  // the diagonal, first in its column
    for (; k < end; ++k) {
      sum += values[k] * in[rows[k]];
      out[rows[k]] += values[k] * x_j;
    }
    out[j] += sum;
  }
}

void ConjugateGradientSolver::PreparePreconditioner(const Eigen::SparseMatrix<double>& A) {
  if (options_.preconditioner == PreconditionerKind::kLaggedCholesky) {
    factored_this_solve_ =
        !factor_.is_factored() || excess_iterations_ >= options_.refactor_budget_iterations;
    if (factored_this_solve_) {
      ++num_factorizations_;
      factor_.Factorize(A);
      excess_iterations_ = 0;
    }
    use_factor_ = factor_.is_factored();
    if (use_factor_) return;
    // A not positive definite at factorisation: fall through to block Jacobi for this solve.
  }
  use_factor_ = false;
  const int num_nodes = static_cast<int>(A.rows() / 3);
  block_inverse_.resize(num_nodes);
  for (int n = 0; n < num_nodes; ++n) {
    Eigen::Matrix3d block;
    for (int c = 0; c < 3; ++c)
      for (int r = c; r < 3; ++r) block(r, c) = block(c, r) = A.coeff(3 * n + r, 3 * n + c);
    block_inverse_[n] = block.inverse();
  }
}

void ConjugateGradientSolver::ApplyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd* z) {
  if (use_factor_) {
    if (options_.factor_precision != FactorPrecision::kDouble)
      factor_.SolveWithCopy(r, z);
    else
      factor_.Solve(r, z);
    return;
  }
  for (size_t n = 0; n < block_inverse_.size(); ++n)
    z->segment<3>(3 * n) = block_inverse_[n] * r.segment<3>(3 * n);
}

SolveReport ConjugateGradientSolver::Solve(const Eigen::SparseMatrix<double>& A,
                                           const Eigen::VectorXd& b, double relative_tolerance,
                                           Eigen::VectorXd* x) {
  const Eigen::Index n = b.size();
  if (x->size() != n) x->setZero(n);
  r_.resize(n), z_.resize(n), p_.resize(n), Ap_.resize(n);
  PreparePreconditioner(A);
  SolveReport report;
  const double b_norm = b.norm();
  if (b_norm == 0.0) {
    x->setZero();
    report.converged = true;
    return report;
  }
  const double target = relative_tolerance * b_norm;
  MultiplySymmetric(A, *x, &Ap_);
  r_ = b - Ap_;
  double r_norm = r_.norm();
  // A warm start that does not already meet the tolerance is scaled to the best multiple of itself
  // in A's norm, α = xᵀb / xᵀAx: no worse there than x (α = 1) or zero (α = 0), and A x is at
  // hand. (Not one that meets it: α is best in A's norm, the test is on the residual's 2-norm.)
  const double x_A_x = x->dot(Ap_);
  const double scale = x_A_x > 0.0 ? x->dot(b) / x_A_x : 1.0;
  if (r_norm > target && std::isfinite(scale) && scale != 1.0) {
    *x *= scale;
    r_ = b - scale * Ap_;
    r_norm = r_.norm();
  }
  double rz = 0.0;
  if (r_norm > target) {  // else no iteration follows, and the apply would go unused
    ApplyPreconditioner(r_, &z_);
    p_ = z_;
    rz = r_.dot(z_);
  }
  while (r_norm > target && report.iterations < options_.max_iterations) {
    MultiplySymmetric(A, p_, &Ap_);
    const double alpha = rz / p_.dot(Ap_);
    *x += alpha * p_;
    r_ -= alpha * Ap_;
    r_norm = r_.norm();
    ++report.iterations;
    // Converged: the next direction would never be used. With a fresh lagged factor CG mostly
    // stops after one iteration, so skipping this apply halves the triangular solves of a step.
    if (r_norm <= target) break;
    ApplyPreconditioner(r_, &z_);
    const double rz_next = r_.dot(z_);
    p_ = z_ + (rz_next / rz) * p_;
    rz = rz_next;
  }
  if (factored_this_solve_) baseline_iterations_ = report.iterations;
  excess_iterations_ += std::max(0, report.iterations - baseline_iterations_);
  report.relative_residual = r_norm / b_norm;
  report.converged = r_norm <= target;
  return report;
}

}  // namespace hapsim::fem
