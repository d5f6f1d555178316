#pragma once
// The forward and backward sweeps of SinglePrecisionFactor::SolveColumns
// (fem/single_precision_factor.h) for several right-hand sides at once, written once over raw
// pointers and instantiated twice: with portable kernels (single_precision_factor.cc) and with AVX2
// intrinsics in a file of their own, built for that instruction set (float_column_sweeps_avx2.cc).
// As with the binary16 sweeps (fem/half_precision_sweeps.h), every function here has internal
// linkage (static), so no copy compiled for AVX2 can stand in for another file's portable one.
//
// Why not Eigen's products, as before: the portable build gives Eigen SSE only (4 floats), and
// its matrix products pack both operands for every supernode; a new contact node's columns are a
// few right-hand sides (3 per node), where that packing cost about as much as the arithmetic.
//
// Y holds the right-hand sides row by row, `width` floats a row (a multiple of 8, padded with
// zeros): each entry of L meets a whole row of Y at once. Every entry of Y is computed by the
// same operations in the same order whatever the kernels (no fused multiply-add), so both give
// the same bits.

namespace hapsim::fem::float_columns {

struct SweepArgs {
  int num_supernodes;
  const int *super, *pi, *px, *s;
  const float* values;  // L in CHOLMOD's supernodal layout (fem/supernodal_layout.h)
  float* Y;             // the permuted right-hand sides, then the solution: n rows of width
  int width;            // floats a row of Y, a multiple of 8
  float* scratch;       // max_rows_below rows of width
  const char* needed;   // per supernode, whether its backward step runs (null: all)
};

// Kernels K, over rows of `width` floats (a multiple of 8); L column-major with leading
// dimension lda:
//   K::SubtractProduct(L, lda, rows, cols, X, out, width): out_i ← out_i − Σ_c L(i, c) X_c for
//     i < rows, the sum's terms subtracted one at a time in order of c;
//   K::SubtractTransposedProduct(L, lda, rows, cols, known, Z, width): Z_c ← Z_c − Σ_i L(i, c)
//     known_i for c < cols, the terms subtracted one at a time in order of i.

// The diagonal block's triangle, one column at a time through the kernels (so that the sums run
// in registers, not through memory):
//   forward:  Y_c ← Y_c / L(c, c), then Y_r ← Y_r − L(r, c) Y_c for the rows r > c;
//   backward: from the last column, Y_c ← (Y_c − Σ_{r>c} L(r, c) Y_r) / L(c, c), in order of r.
template <class K>
static inline void SolveDiagonalForward(const float* block, long lda, int cols, float* Y_cols,
                                        int width) {
  for (int c = 0; c < cols; ++c) {
    const float* column = block + c * lda;
    float* y_c = Y_cols + static_cast<long>(c) * width;
    for (int j = 0; j < width; ++j) y_c[j] = y_c[j] / column[c];
    K::SubtractProduct(column + c + 1, lda, cols - c - 1, 1, y_c, y_c + width, width);
  }
}
template <class K>
static inline void SolveDiagonalBackward(const float* block, long lda, int cols, float* Y_cols,
                                         int width) {
  for (int c = cols - 1; c >= 0; --c) {
    const float* column = block + c * lda;
    float* y_c = Y_cols + static_cast<long>(c) * width;
    K::SubtractTransposedProduct(column + c + 1, lda, cols - c - 1, 1, y_c + width, y_c, width);
    for (int j = 0; j < width; ++j) y_c[j] = y_c[j] / column[c];
  }
}

static inline bool IsZero(const float* rows, long count) {
  for (long i = 0; i < count; ++i)
    if (rows[i] != 0.0f) return false;
  return true;
}

// Y ← L⁻¹ Y, skipping the supernodes whose rows of Y are still zero (L⁻¹ keeps zero what no
// earlier column reached: for a node's columns of the identity, all but its elimination-tree
// path), then Y ← L⁻ᵀ Y on the needed supernodes only (a backward step reads only its ancestors'
// rows, and a needed supernode's ancestors are needed too).
template <class K>
static inline void SolveColumns(const SweepArgs& a) {
  const int w = a.width;
  for (int sn = 0; sn < a.num_supernodes; ++sn) {
    const int k1 = a.super[sn], nscol = a.super[sn + 1] - k1;
    const int nsrow = a.pi[sn + 1] - a.pi[sn], below = nsrow - nscol;
    float* Y_cols = a.Y + static_cast<long>(k1) * w;
    if (IsZero(Y_cols, static_cast<long>(nscol) * w)) continue;
    const float* block = a.values + a.px[sn];
    SolveDiagonalForward<K>(block, nsrow, nscol, Y_cols, w);
    if (below == 0) continue;
    for (long i = 0; i < static_cast<long>(below) * w; ++i) a.scratch[i] = 0.0f;
    K::SubtractProduct(block + nscol, nsrow, below, nscol, Y_cols, a.scratch, w);
    const int* rows = a.s + a.pi[sn] + nscol;
    for (int i = 0; i < below; ++i) {
      float* y = a.Y + static_cast<long>(rows[i]) * w;
      const float* update = a.scratch + static_cast<long>(i) * w;
      for (int j = 0; j < w; ++j) y[j] = y[j] + update[j];
    }
  }
  for (int sn = a.num_supernodes - 1; sn >= 0; --sn) {
    if (a.needed && !a.needed[sn]) continue;
    const int k1 = a.super[sn], nscol = a.super[sn + 1] - k1;
    const int nsrow = a.pi[sn + 1] - a.pi[sn], below = nsrow - nscol;
    float* Y_cols = a.Y + static_cast<long>(k1) * w;
    const float* block = a.values + a.px[sn];
    if (below > 0) {
      const int* rows = a.s + a.pi[sn] + nscol;
      for (int i = 0; i < below; ++i) {
        const float* y = a.Y + static_cast<long>(rows[i]) * w;
        float* known = a.scratch + static_cast<long>(i) * w;
        for (int j = 0; j < w; ++j) known[j] = y[j];
      }
      K::SubtractTransposedProduct(block + nscol, nsrow, below, nscol, a.scratch, Y_cols, w);
    }
    SolveDiagonalBackward<K>(block, nsrow, nscol, Y_cols, w);
  }
}

}  // namespace hapsim::fem::float_columns

namespace hapsim::fem::float_columns {
// SolveColumns with the AVX2 kernels (float_column_sweeps_avx2.cc; x86-64 only, and only on a CPU
// with AVX2).
void SolveColumnsWithAvx2(const SweepArgs& args);
}  // namespace hapsim::fem::float_columns
