#pragma once
// A single-precision copy of a supernodal CHOLMOD factor A = Pᵀ L Lᵀ P, and its two triangular
// solves: z ≈ A⁻¹ r as a preconditioner for double-precision CG (issue 13: "a single-precision
// factor inside double-precision CG").
//
// Why. With a lagged factor CG needs 1–5 iterations, and each is one forward and one backward
// solve with L: on the 28.8k-tet block L has 4.1 M nonzeros, 33 MB in double, more than this
// machine's 32 MB L3, so every solve streams L from memory twice. In float it is 16 MB and stays
// in cache. The preconditioner only has to be close to A⁻¹, not exact: L rounded to float
// changes M⁻¹A by about 6e-8 · κ(A), which leaves a residual near CG's 1e-6 tolerance after a
// fresh factor's one iteration: about one step in six then takes a second (FemOptions,
// FactorPrecision). CG itself, its residual and its stopping test stay in double, so the answer
// is as accurate as before (tests/fem/time_stepper_test.cc, against CHOLMOD).

#include <cholmod.h>

#include <Eigen/Core>
#include <vector>

#include "fem/supernodal_layout.h"

namespace hapsim::fem {

class SinglePrecisionFactor {
 public:
  // Copies L (supernodal, LLᵀ, real, double, int indices) rounded to float. Throws
  // std::invalid_argument for any other kind of factor.
  void Assign(const cholmod_factor& L);

  // x = Pᵀ L⁻ᵀ L⁻¹ P b, in single precision (b and x in double). Allocates nothing once sized.
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) const;

  // kFastest: the AVX2 kernels of SolveColumns where the CPU has them, else the portable ones
  // (the same bits either way; tests compare them).
  enum class Kernels { kFastest, kPortable };
  static bool CpuHasVectorKernels();

  // X = Pᵀ L⁻ᵀ L⁻¹ P B for several columns at once, each entry of L read once for up to 24 of
  // them (fem/float_column_sweeps.h). The forward sweep skips the supernodes where every column is
  // still zero: for a B with a few nonzero rows (a node's columns of the identity) only those on
  // the elimination tree's paths from them to the root do any work. Allocates (for the visual
  // frame, not the haptic step).
  Eigen::MatrixXd SolveColumns(const Eigen::MatrixXd& B, Kernels kernels = Kernels::kFastest) const;
  // The rows wanted_rows (original indices, in that order) of the same X, bit for bit: the
  // backward sweep works only on the supernodes that hold them and on their ancestors in the
  // elimination tree, which is all a backward step reads. For the warped compliance, which reads
  // A₀⁻¹ only at contact nodes: with the ~450 top nodes block_press_large touches, about two
  // thirds of the time of all rows at 28.8k tets (BM_SolveColumns). Throws
  // std::invalid_argument if B's rows or a wanted row do not fit the factor.
  Eigen::MatrixXd SolveColumnsAt(const Eigen::MatrixXd& B, const std::vector<int>& wanted_rows,
                                 Kernels kernels = Kernels::kFastest) const;

  bool empty() const { return layout_.empty(); }

 private:
  // Y = L⁻ᵀ L⁻¹ P B row by row, *width floats a row (B's columns padded to a multiple of 8);
  // needed: per supernode, whether its backward step runs (null: all; the rows of those skipped
  // are left as the forward sweep left them).
  std::vector<float> SolvePermutedColumns(const Eigen::MatrixXd& B, const std::vector<char>* needed,
                                          Kernels kernels, int* width) const;

  SupernodalLayout layout_;
  std::vector<float> values_;
  mutable Eigen::VectorXf y_, gathered_;  // scratch: the permuted vector; a supernode's rows
};

}  // namespace hapsim::fem
