// SinglePrecisionFactor's multi-column sweeps with AVX2 intrinsics (fem/float_column_sweeps.h).
// This file alone is built with -mavx2 (fem/CMakeLists.txt) and is called only on a CPU that has
// it (SinglePrecisionFactor::CpuHasVectorKernels). It includes only <immintrin.h> and the sweeps'
// header, and uses no inline function with external linkage (no Eigen, no standard containers),
// so that no AVX2 copy of one is emitted to replace another file's. Keep it so.
#if defined(__x86_64__)

#include <immintrin.h>

#include "fem/float_column_sweeps.h"

namespace hapsim::fem::float_columns {
namespace {

// Both products take up to 24 right-hand sides (V registers of eight) and four columns of L at a
// time, each entry of Y subtracting its terms one by one in the order the portable loops use. (With
// eight at a time, eight nodes' 24 columns streamed L three times, and took as long as before.)
template <int V>
void SubtractProductChunk(const float* L, long lda, int rows, int cols, const float* X, float* out,
                          int width) {
  for (int c0 = 0; c0 < cols; c0 += 4) {
    const int m = cols - c0 < 4 ? cols - c0 : 4;
    __m256 x[4][V];
    for (int q = 0; q < m; ++q)
      for (int v = 0; v < V; ++v)
        x[q][v] = _mm256_loadu_ps(X + static_cast<long>(c0 + q) * width + 8 * v);
    const float* column = L + c0 * lda;
    for (int i = 0; i < rows; ++i) {
      float* o = out + static_cast<long>(i) * width;
      __m256 acc[V];
      for (int v = 0; v < V; ++v) acc[v] = _mm256_loadu_ps(o + 8 * v);
      for (int q = 0; q < m; ++q) {
        const __m256 l = _mm256_set1_ps(column[q * lda + i]);
        for (int v = 0; v < V; ++v) acc[v] = _mm256_sub_ps(acc[v], _mm256_mul_ps(l, x[q][v]));
      }
      for (int v = 0; v < V; ++v) _mm256_storeu_ps(o + 8 * v, acc[v]);
    }
  }
}

template <int V>
void SubtractTransposedProductChunk(const float* L, long lda, int rows, int cols,
                                    const float* known, float* Z, int width) {
  for (int c0 = 0; c0 < cols; c0 += 4) {
    const int m = cols - c0 < 4 ? cols - c0 : 4;
    __m256 acc[4][V];
    for (int q = 0; q < m; ++q)
      for (int v = 0; v < V; ++v)
        acc[q][v] = _mm256_loadu_ps(Z + static_cast<long>(c0 + q) * width + 8 * v);
    const float* column = L + c0 * lda;
    for (int i = 0; i < rows; ++i) {
      __m256 k[V];
      for (int v = 0; v < V; ++v)
        k[v] = _mm256_loadu_ps(known + static_cast<long>(i) * width + 8 * v);
      for (int q = 0; q < m; ++q) {
        const __m256 l = _mm256_set1_ps(column[q * lda + i]);
        for (int v = 0; v < V; ++v) acc[q][v] = _mm256_sub_ps(acc[q][v], _mm256_mul_ps(l, k[v]));
      }
    }
    for (int q = 0; q < m; ++q)
      for (int v = 0; v < V; ++v)
        _mm256_storeu_ps(Z + static_cast<long>(c0 + q) * width + 8 * v, acc[q][v]);
  }
}

struct Avx2Kernels {
  static void SubtractProduct(const float* L, long lda, int rows, int cols, const float* X,
                              float* out, int width) {
    for (int j = 0; j < width;) {
      const int left = (width - j) / 8;
      if (left >= 3) {
        SubtractProductChunk<3>(L, lda, rows, cols, X + j, out + j, width), j += 24;
      } else if (left == 2) {
        SubtractProductChunk<2>(L, lda, rows, cols, X + j, out + j, width), j += 16;
      } else {
        SubtractProductChunk<1>(L, lda, rows, cols, X + j, out + j, width), j += 8;
      }
    }
  }

  static void SubtractTransposedProduct(const float* L, long lda, int rows, int cols,
                                        const float* known, float* Z, int width) {
    for (int j = 0; j < width;) {
      const int left = (width - j) / 8;
      if (left >= 3) {
        SubtractTransposedProductChunk<3>(L, lda, rows, cols, known + j, Z + j, width), j += 24;
      } else if (left == 2) {
        SubtractTransposedProductChunk<2>(L, lda, rows, cols, known + j, Z + j, width), j += 16;
      } else {
        SubtractTransposedProductChunk<1>(L, lda, rows, cols, known + j, Z + j, width), j += 8;
      }
    }
  }
};

}  // namespace

void SolveColumnsWithAvx2(const SweepArgs& args) { SolveColumns<Avx2Kernels>(args); }

}  // namespace hapsim::fem::float_columns

#endif  // defined(__x86_64__)
