#pragma once
// Direct solve by a sparse Cholesky factorisation refreshed at every call (CHOLMOD supernodal;
// the symbolic analysis is reused while the pattern holds).

#include "fem/cholmod_factor.h"
#include "fem/linear_solver.h"

namespace hapsim::fem {

class CholmodSolver final : public LinearSolver {
 public:
  SolveReport Solve(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b,
                    double relative_tolerance, Eigen::VectorXd* x) override;
  // With the factor of the last Solve, if it succeeded (else as Solve: factors A).
  SolveReport SolveAgain(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b,
                         double relative_tolerance, Eigen::VectorXd* x) override;
  CholmodFactor* factor() override { return &factor_; }
  void AnalyzePattern(const Eigen::SparseMatrix<double>& A) override { factor_.Analyze(A); }
  int num_factorizations() const override { return num_factorizations_; }

 private:
  // x = factor⁻¹ b and its report (the factor holds A).
  SolveReport SolveWithFactor(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b,
                              Eigen::VectorXd* x);

  CholmodFactor factor_;
  int num_factorizations_ = 0;
  Eigen::VectorXd residual_;  // scratch
};

}  // namespace hapsim::fem
