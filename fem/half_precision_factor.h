#pragma once
// A half-precision (IEEE binary16) copy of a supernodal CHOLMOD factor A = Pᵀ L Lᵀ P, and its
// two triangular solves: z ≈ A⁻¹ r as a preconditioner for double-precision CG, at half the
// memory traffic of the float copy (fem/single_precision_factor.h).
//
// Why. Each CG iteration with a lagged factor is one forward and one backward solve with L, and
// on the 28.8k-tet block they stream L (4.1 M nonzeros): 16 MB in float, against the 32 MB L3,
// shared with everything else, of the AMD VM this was first measured on. With a stale factor a
// visual frame of block_press_large makes ~9 of them, more than half its time (issue 13). In
// binary16 L is 8 MB. The entries keep 11 significant bits (relative rounding 2⁻¹¹ ≈ 4.9e-4): a
// preconditioner need only be near A⁻¹, and a factor several frames old is further from it than
// that. CG, its residual and its stopping test stay in double, so answers are as accurate as
// before.
//
// Range. binary16 holds 6.1e-5 … 65504 (subnormals down to 6e-8). L is stored scaled by a power
// of two s that puts its largest entry between 2¹³ and 2¹⁴, so the solve loses only entries below
// ~2⁻³⁸ of the largest; x is multiplied by s² at the end (exact). The diagonal, whose
// reciprocal each column multiplies by, is kept in float.
//
// Kernels. On a CPU with AVX2 and F16C (x86-64 since 2013) the column loops convert eight
// entries an instruction (fem/half_precision_factor_avx2.cc); elsewhere portable loops do the
// same arithmetic in the same order, so both give the same bits (tested).

#include <cholmod.h>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fem/supernodal_layout.h"

namespace hapsim::fem {

class HalfPrecisionFactor {
 public:
  // Copies L (supernodal, LLᵀ, real, double, int indices), scaled and rounded to binary16.
  // Throws std::invalid_argument for any other kind of factor.
  void Assign(const cholmod_factor& L);

  // kFastest: the AVX2 + F16C kernels where the CPU has them, else the portable ones (the same
  // bits either way; tests compare them).
  enum class Kernels { kFastest, kPortable };
  static bool CpuHasVectorKernels();

  // out[k] = float(scale · x[k]) rounded to binary16 (to nearest, ties to even), as Assign stores
  // L: eight entries an instruction with F16C (a refactorisation at 28.8k tets converts 4.1 M).
  static void ConvertToHalf(const double* x, double scale, long n, std::uint16_t* out,
                            Kernels kernels = Kernels::kFastest);

  // x = Pᵀ L⁻ᵀ L⁻¹ P b, the sums in single precision (b and x in double). Allocates nothing
  // once sized.
  void Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x,
             Kernels kernels = Kernels::kFastest) const;

  bool empty() const { return layout_.empty(); }

 private:
  SupernodalLayout layout_;
  std::vector<std::uint16_t> values_;    // s·L in binary16, CHOLMOD's layout
  std::vector<float> inverse_diagonal_;  // 1 / (s·L(k, k)), by permuted index k
  double scale_ = 1.0;                   // s, a power of two
  mutable Eigen::VectorXf y_, scratch_;  // the permuted vector; one supernode's rows
};

}  // namespace hapsim::fem
