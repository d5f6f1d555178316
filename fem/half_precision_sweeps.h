#pragma once
// The forward and backward sweeps of HalfPrecisionFactor::Solve (fem/half_precision_factor.h),
// written once over raw pointers and instantiated twice: with portable kernels
// (half_precision_factor.cc) and with AVX2 + F16C intrinsics in a file of their own, built with
// those instruction sets (half_precision_factor_avx2.cc). The sweeps and HalfToFloat have internal
// linkage (static), so no copy compiled for AVX2 can stand in for another file's portable one.

#include <cstdint>

namespace hapsim::fem::half_sweeps {

// What a solve reads and writes: the supernodal layout (fem/supernodal_layout.h), s·L in
// binary16, the reciprocals of its diagonal in float, the permuted vector y (in, then out) and
// scratch of max_rows floats (one supernode's rows).
struct SweepArgs {
  int num_supernodes;
  const int *super, *pi, *px, *s;
  const std::uint16_t* values;
  const float* inverse_diagonal;
  float* y;
  float* scratch;
};

// A supernode's columns are taken kBlockColumns at a time. Why: one column at a time, the backward
// sweep's dot product is a single chain of dependent adds, and the forward sweep loads and stores
// the rows it updates once per column. A block of columns shares the loads of the vector it reads
// and gives the dot products independent chains. With the block's triangle in registers
// (SolveBlockForward/Backward), one apply at 28.8k tets took 1.18 ms against 1.50 column by column
// (BM_FactorSolve, 2026-11-26 on an Intel Xeon); 8 columns a block measured no faster than 4.
constexpr int kBlockColumns = 4;

// Kernels K, for m ≤ kBlockColumns columns a_k = a + k·lda of binary16 entries:
//   K::ToFloat(h): one binary16 entry as float (exact);
//   K::SubtractColumns<m>(a, lda, c, z, n): z[i] ← (…((z[i] − a_0[i]·c[0]) − a_1[i]·c[1]) …) −
//     a_{m−1}[i]·c[m−1] for i < n, i.e. in column order, as one column at a time would;
//   K::DotColumns<m>(a, lda, x, n, dots): dots[k] = Σ_i a_k[i] x[i], with the sums in the order
//     both kernels share: eight lanes (lane j takes i ≡ j mod 8 of the first n − n mod 8), then
//     lanes 0..7 added in order, then the rest in order.
// No fused multiply-add, so every CPU rounds alike.

// f(Columns<m>()) for a run-time count m in 1 .. kBlockColumns: the kernels and the block
// triangles take m at compile time, so that their loops over a block's columns unroll.
template <int m>
struct Columns {
  static constexpr int value = m;
};
template <int m = kBlockColumns, class F>
static inline void WithBlockColumns(int count, F&& f) {
  if constexpr (m > 1)
    if (count < m) return WithBlockColumns<m - 1>(count, f);
  f(Columns<m>());
}

// Supernode sn's rows gathered into z: its columns' y (z[0 .. nscol)) then the rows below. Column
// c of the block is L's entries at those rows: z[r] pairs with column[r].
struct Supernode {
  int first_column, num_columns, num_rows;
  const std::uint16_t* block;  // column-major, num_rows a column
  const int* rows_below;       // y's indices of z[num_columns ..]
};

static inline Supernode GetSupernode(const SweepArgs& a, int sn) {
  return {a.super[sn], a.super[sn + 1] - a.super[sn], a.pi[sn + 1] - a.pi[sn], a.values + a.px[sn],
          a.s + a.pi[sn] + (a.super[sn + 1] - a.super[sn])};
}

// The triangle of one block of m columns, c0 .. c0 + m − 1, with t = z[c0 ..] held in registers
// (m is known at compile time, so the loops unroll): each column's entry waits on the one before,
// a chain of dependent operations per column of L, so it is kept short: a product with the
// diagonal's reciprocal instead of a division, no store and reload between columns.
//   forward:  t_k ← t_k / L_kk, then t_r ← t_r − L_rk t_k for the rows r > k of the block;
//   backward: t_k ← (t_k − dots_k − Σ_{r>k} L_rk t_r) / L_kk, from the last column, the sum in
//             order of r.
// diagonal_block points at entry (c0, c0): column k's entry at row r is diagonal_block[k·lda + r].
template <class K, int m>
static inline void SolveBlockForward(const std::uint16_t* diagonal_block, long lda,
                                     const float* inverse_diagonal, float* z) {
  float t[m];
  for (int k = 0; k < m; ++k) t[k] = z[k];
  for (int k = 0; k < m; ++k) {
    t[k] = t[k] * inverse_diagonal[k];
    for (int r = k + 1; r < m; ++r) t[r] = t[r] - K::ToFloat(diagonal_block[k * lda + r]) * t[k];
  }
  for (int k = 0; k < m; ++k) z[k] = t[k];
}
template <class K, int m>
static inline void SolveBlockBackward(const std::uint16_t* diagonal_block, long lda,
                                      const float* inverse_diagonal, const float* dots, float* z) {
  float t[m];
  for (int k = m - 1; k >= 0; --k) {
    float sum = z[k] - dots[k];
    for (int r = k + 1; r < m; ++r) sum = sum - K::ToFloat(diagonal_block[k * lda + r]) * t[r];
    t[k] = sum * inverse_diagonal[k];
  }
  for (int k = 0; k < m; ++k) z[k] = t[k];
}
// y ← (sL)⁻¹ y, supernode by supernode. Within one, a block of columns at a time: its own
// triangle, then every row below the block at once. Each z[r] still receives the columns c < r in
// order, as a column-at-a-time sweep would. The rows below the diagonal block are added back into
// y when the supernode is done.
template <class K>
static inline void ForwardSweep(const SweepArgs& a) {
  float* z = a.scratch;
  for (int sn = 0; sn < a.num_supernodes; ++sn) {
    const Supernode n = GetSupernode(a, sn);
    for (int r = 0; r < n.num_columns; ++r) z[r] = a.y[n.first_column + r];
    for (int r = n.num_columns; r < n.num_rows; ++r) z[r] = 0.0f;
    for (int c0 = 0; c0 < n.num_columns; c0 += kBlockColumns) {
      const int end = c0 + kBlockColumns < n.num_columns ? c0 + kBlockColumns : n.num_columns;
      const std::uint16_t* block_columns = n.block + static_cast<long>(c0) * n.num_rows;
      WithBlockColumns(end - c0, [&](auto columns) {
        constexpr int m = decltype(columns)::value;
        SolveBlockForward<K, m>(block_columns + c0, n.num_rows,
                                a.inverse_diagonal + n.first_column + c0, z + c0);
        K::template SubtractColumns<m>(block_columns + end, n.num_rows, z + c0, z + end,
                                       n.num_rows - end);
      });
    }
    for (int r = 0; r < n.num_columns; ++r) a.y[n.first_column + r] = z[r];
    for (int r = n.num_columns; r < n.num_rows; ++r) a.y[n.rows_below[r - n.num_columns]] += z[r];
  }
}

// y ← (sL)⁻ᵀ y, in reverse. Within a supernode, blocks of columns from the last: the block's dot
// products with every row below it at once, then its own triangle.
template <class K>
static inline void BackwardSweep(const SweepArgs& a) {
  float* z = a.scratch;
  float dots[kBlockColumns];
  for (int sn = a.num_supernodes - 1; sn >= 0; --sn) {
    const Supernode n = GetSupernode(a, sn);
    for (int r = 0; r < n.num_columns; ++r) z[r] = a.y[n.first_column + r];
    for (int r = n.num_columns; r < n.num_rows; ++r) z[r] = a.y[n.rows_below[r - n.num_columns]];
    const int last_block = (n.num_columns - 1) / kBlockColumns * kBlockColumns;
    for (int c0 = last_block; c0 >= 0; c0 -= kBlockColumns) {
      const int end = c0 + kBlockColumns < n.num_columns ? c0 + kBlockColumns : n.num_columns;
      const std::uint16_t* block_columns = n.block + static_cast<long>(c0) * n.num_rows;
      WithBlockColumns(end - c0, [&](auto columns) {
        constexpr int m = decltype(columns)::value;
        K::template DotColumns<m>(block_columns + end, n.num_rows, z + end, n.num_rows - end, dots);
        SolveBlockBackward<K, m>(block_columns + c0, n.num_rows,
                                 a.inverse_diagonal + n.first_column + c0, dots, z + c0);
      });
    }
    for (int r = 0; r < n.num_columns; ++r) a.y[n.first_column + r] = z[r];
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
// out[k] = binary16 of float(scale · x[k]), each rounding to nearest (ties to even), with F16C.
void ConvertToHalfWithAvx2(const double* x, double scale, long n, std::uint16_t* out);
}  // namespace hapsim::fem::half_sweeps
