#pragma once
// A sparse Cholesky factor A = L Lᵀ held by CHOLMOD (supernodal). The ordering and symbolic
// analysis are done when the pattern is first seen and reused while it holds; Factorize() then
// only redoes the numeric part. Solve() reuses its workspaces, so it allocates nothing after the
// first call. Used directly (CholmodSolver) and as a lagged preconditioner for CG.

#include <cholmod.h>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "fem/fem_options.h"
#include "fem/half_precision_factor.h"
#include "fem/single_precision_factor.h"
#include "fem/supernodal_layout.h"

namespace hapsim::fem {

class CholmodFactor {
 public:
  CholmodFactor();
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;

  // Ordering and symbolic analysis of A's pattern (compressed), unless already done for it: all
  // that depends on the mesh alone, so a caller that knows the pattern early can do it at set-up
  // (the first step's solve is ~40 ms shorter for it on the 28.8k-tet block, ~10 ms on the 3.6k
  // one, where a numeric factorisation then took ~250 and ~17 ms; 108 and 4.9 ms on one thread).
  // Factorize calls it.
  void Analyze(const Eigen::SparseMatrix<double>& A);

  // Factors symmetric A (full or lower storage, compressed; only the lower half is read).
  // Returns false if A is not positive definite. Throws std::runtime_error if CHOLMOD fails
  // for another reason (out of memory).
  bool Factorize(const Eigen::SparseMatrix<double>& A);

  // x = A⁻¹ b with the last successful factor. Precondition: Factorize returned true.
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x);

  // Keep a reduced-precision copy of every factor from now on, for SolveWithCopy: kSingle a
  // float one (SinglePrecisionFactor: x ≈ A⁻¹ b to float accuracy, about twice as fast as Solve
  // on large factors), kHalf a binary16 one (HalfPrecisionFactor: half the bytes again, entries
  // to 4.9e-4). kDouble keeps none.
  void KeepCopy(FactorPrecision precision) { copy_precision_ = precision; }
  void SolveWithCopy(const Eigen::VectorXd& b, Eigen::VectorXd* x) const;
  // X ≈ A⁻¹ B for several columns with the float copy (SinglePrecisionFactor::SolveColumns).
  // Precondition: KeepCopy(kSingle), and Factorize returned true.
  Eigen::MatrixXd SolveColumnsWithCopy(const Eigen::MatrixXd& B) const;
  // Its rows wanted_rows only (SinglePrecisionFactor::SolveColumnsAt).
  Eigen::MatrixXd SolveColumnsWithCopyAt(const Eigen::MatrixXd& B,
                                         const std::vector<int>& wanted_rows) const;
  // The binary16 and float copies (empty unless kept and factored).
  const HalfPrecisionFactor& half_precision_copy() const { return half_; }
  const SinglePrecisionFactor& single_precision_copy() const { return single_; }

  // X = A⁻¹ B for a dense B of several columns, in one supernodal solve (BLAS-3 across the
  // columns). Precondition: Factorize returned true.
  Eigen::MatrixXd SolveColumns(const Eigen::MatrixXd& B);

  // J A⁻¹ Jᵀ for sparse J (rows x n), solved only on the supernodes J's dofs reach
  // (fem/inverse_quadratic_form.h). Precondition: Factorize returned true. Returns a dense
  // symmetric (rows x rows) matrix.
  Eigen::MatrixXd CalcInverseQuadraticForm(const Eigen::SparseMatrix<double>& J);

  bool is_factored() const { return factored_; }
  // From the symbolic analysis (0 before): nonzeros of L, and flops of one numeric factorisation.
  double num_factor_nonzeros() const { return factor_ ? common_.lnz : 0.0; }
  double factorization_flops() const { return factor_ ? common_.fl : 0.0; }

 private:
  cholmod_common common_;
  cholmod_factor* factor_ = nullptr;
  Eigen::Index analysed_nonzeros_ = -1;
  bool factored_ = false;
  FactorPrecision copy_precision_ = FactorPrecision::kDouble;  // kDouble: no copy
  SinglePrecisionFactor single_;
  HalfPrecisionFactor half_;
  SupernodalLayout layout_;  // L's structure, for CalcInverseQuadraticForm; empty until then
  cholmod_dense* solution_ = nullptr;  // reused by cholmod_solve2
  cholmod_dense* work_y_ = nullptr;
  cholmod_dense* work_e_ = nullptr;
};

}  // namespace hapsim::fem
