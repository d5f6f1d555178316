// HalfPrecisionFactor's sweeps with AVX2 + F16C intrinsics (fem/half_precision_sweeps.h). This
// file alone is built with -mavx2 -mf16c (fem/CMakeLists.txt) and is called only on a CPU that
// has both (HalfPrecisionFactor::CpuHasVectorKernels). It includes only <immintrin.h> and the
// sweeps' header, and uses no inline function with external linkage (no Eigen, no standard
// containers), so that no AVX2 copy of one is emitted to replace another file's. Keep it so.
#if defined(__x86_64__)

#include <immintrin.h>

#include "fem/half_precision_sweeps.h"

namespace hapsim::fem::half_sweeps {
namespace {

// Eight binary16 entries from a (any alignment) as floats, exactly. (_cvtsh_ss converts one, as
// exactly: the same values as HalfToFloat.)
inline __m256 LoadHalves(const std::uint16_t* a) {
  return _mm256_cvtph_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(a)));
}

struct Avx2Kernels {
  static float ToFloat(std::uint16_t h) { return _cvtsh_ss(h); }

  template <int m>
  static void SubtractColumns(const std::uint16_t* a, long lda, const float* c, float* z, int n) {
    __m256 c8[m];
    for (int k = 0; k < m; ++k) c8[k] = _mm256_set1_ps(c[k]);
    int i = 0;
    for (; i + 8 <= n; i += 8) {
      __m256 value = _mm256_loadu_ps(z + i);
      for (int k = 0; k < m; ++k)
        value = _mm256_sub_ps(value, _mm256_mul_ps(LoadHalves(a + k * lda + i), c8[k]));
      _mm256_storeu_ps(z + i, value);
    }
    for (; i < n; ++i) {
      float value = z[i];
      for (int k = 0; k < m; ++k) value = value - _cvtsh_ss(a[k * lda + i]) * c[k];
      z[i] = value;
    }
  }

  template <int m>
  static void DotColumns(const std::uint16_t* a, long lda, const float* x, int n, float* dots) {
    __m256 lanes8[m];
    for (int k = 0; k < m; ++k) lanes8[k] = _mm256_setzero_ps();
    const int n8 = n - n % 8;
    for (int i = 0; i < n8; i += 8) {
      const __m256 x8 = _mm256_loadu_ps(x + i);
      for (int k = 0; k < m; ++k)
        lanes8[k] = _mm256_add_ps(lanes8[k], _mm256_mul_ps(LoadHalves(a + k * lda + i), x8));
    }
    for (int k = 0; k < m; ++k) {
      alignas(32) float lanes[8];
      _mm256_store_ps(lanes, lanes8[k]);
      float sum = lanes[0];
      for (int j = 1; j < 8; ++j) sum += lanes[j];
      for (int i = n8; i < n; ++i) sum += _cvtsh_ss(a[k * lda + i]) * x[i];
      dots[k] = sum;
    }
  }
};

}  // namespace

void SolveWithAvx2(const SweepArgs& args) {
  ForwardSweep<Avx2Kernels>(args);
  BackwardSweep<Avx2Kernels>(args);
}

void ConvertToHalfWithAvx2(const double* x, double scale, long n, std::uint16_t* out) {
  const __m256d scale4 = _mm256_set1_pd(scale);
  long k = 0;
  for (; k + 8 <= n; k += 8) {
    const __m128 low = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_loadu_pd(x + k), scale4));
    const __m128 high = _mm256_cvtpd_ps(_mm256_mul_pd(_mm256_loadu_pd(x + k + 4), scale4));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(out + k),
                     _mm256_cvtps_ph(_mm256_set_m128(high, low), _MM_FROUND_TO_NEAREST_INT));
  }
  for (; k < n; ++k)
    out[k] = _cvtss_sh(static_cast<float>(scale * x[k]), _MM_FROUND_TO_NEAREST_INT);
}

}  // namespace hapsim::fem::half_sweeps

#endif  // defined(__x86_64__)
