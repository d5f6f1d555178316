#pragma once
// The forward and backward sweeps of HalfPrecisionFactor::Solve (fem/half_precision_factor.h),
// written once over raw pointers and instantiated twice: with portable kernels
// (half_precision_factor.cc) and with AVX2 + F16C intrinsics in a file of their own, built with
// those instruction sets (half_precision_factor_avx2.cc). The sweeps and HalfToFloat have internal
// linkage (static), so no copy compiled for AVX2 can stand in for another file's portable one.

#include <cstdint>

namespace hapsim::fem::half_sweeps {

// What a solve reads and writes: the supernodal layout (fem/supernodal_layout.h), s·L in
// binary16, its diagonal in float, the permuted vector y (in, then out) and scratch of
// max_rows_below floats.
struct SweepArgs {
  int num_supernodes;
  const int *super, *pi, *px, *s;
  const std::uint16_t* values;
  const float* diagonal;
  float* y;
  float* scratch;
};

// Kernels K: K::SubtractScaled(a, c, y, n): y[i] −= a[i]·c for i < n; K::Dot(a, x, n) = Σ a[i] x[i]
// with the sums in the order both kernels share: eight lanes (lane j takes i ≡ j mod 8 of the
// first n − n mod 8), then lanes 0..7 added in order, then the rest in order. No fused
// multiply-add, so every CPU rounds alike. (Four accumulators instead of one measured no faster
// at 28.8k tets: the sweeps wait on memory, not on the adds.)

// y ← (sL)⁻¹ y, supernode by supernode, column by column as L is stored: the column's diagonal
// entry, then the rest of its diagonal block (in y), then the rows below (gathered in scratch,
// added to y when the supernode is done).
template <class K>
static inline void ForwardSweep(const SweepArgs& a) {
  for (int sn = 0; sn < a.num_supernodes; ++sn) {
    const int k1 = a.super[sn], nscol = a.super[sn + 1] - k1;
    const int nsrow = a.pi[sn + 1] - a.pi[sn], below = nsrow - nscol;
    const std::uint16_t* block = a.values + a.px[sn];
    float* y_cols = a.y + k1;
    for (int i = 0; i < below; ++i) a.scratch[i] = 0.0f;
    for (int c = 0; c < nscol; ++c) {
      const std::uint16_t* column = block + static_cast<long>(c) * nsrow;
      const float y_c = y_cols[c] / a.diagonal[k1 + c];
      y_cols[c] = y_c;
      K::SubtractScaled(column + c + 1, y_c, y_cols + c + 1, nscol - c - 1);
      K::SubtractScaled(column + nscol, y_c, a.scratch, below);
    }
    const int* rows = a.s + a.pi[sn] + nscol;
    for (int i = 0; i < below; ++i) a.y[rows[i]] += a.scratch[i];
  }
}

// y ← (sL)⁻ᵀ y, in reverse: each column's dot products with the rows below (gathered) and with
// the later columns of its diagonal block, then its diagonal entry.
template <class K>
static inline void BackwardSweep(const SweepArgs& a) {
  for (int sn = a.num_supernodes - 1; sn >= 0; --sn) {
    const int k1 = a.super[sn], nscol = a.super[sn + 1] - k1;
    const int nsrow = a.pi[sn + 1] - a.pi[sn], below = nsrow - nscol;
    const std::uint16_t* block = a.values + a.px[sn];
    float* y_cols = a.y + k1;
    const int* rows = a.s + a.pi[sn] + nscol;
    for (int i = 0; i < below; ++i) a.scratch[i] = a.y[rows[i]];
    for (int c = nscol - 1; c >= 0; --c) {
      const std::uint16_t* column = block + static_cast<long>(c) * nsrow;
      const float sum = y_cols[c] - K::Dot(column + nscol, a.scratch, below) -
                        K::Dot(column + c + 1, y_cols + c + 1, nscol - c - 1);
      y_cols[c] = sum / a.diagonal[k1 + c];
    }
  }
}

// binary16 bits → float, exactly (every binary16 value is a float).
static inline float HalfToFloat(std::uint16_t h) {
  const std::uint32_t sign = static_cast<std::uint32_t>(h & 0x8000u) << 16;
  const std::uint32_t exponent = (h >> 10) & 0x1fu, mantissa = h & 0x3ffu;
  std::uint32_t bits;
  if (exponent == 0) {  // zero or subnormal: mantissa · 2⁻²⁴, exact in float
    float value = static_cast<float>(mantissa) * 5.9604644775390625e-8f;
    return sign ? -value : value;
  }
  if (exponent == 31)
    bits = sign | 0x7f800000u | (mantissa << 13);  // infinity or NaN
  else
    bits = sign | ((exponent + 112u) << 23) | (mantissa << 13);
  float value;
  __builtin_memcpy(&value, &bits, sizeof value);
  return value;
}

}  // namespace hapsim::fem::half_sweeps

namespace hapsim::fem::half_sweeps {
// Both sweeps with the AVX2 + F16C kernels (half_precision_factor_avx2.cc; x86-64 only, and only
// on a CPU with both).
void SolveWithAvx2(const SweepArgs& args);
}  // namespace hapsim::fem::half_sweeps
