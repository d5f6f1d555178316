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
  static void SubtractScaled(const std::uint16_t* a, float c, float* y, int n) {
    const __m256 c8 = _mm256_set1_ps(c);
    int i = 0;
    for (; i + 8 <= n; i += 8)
      _mm256_storeu_ps(y + i,
                       _mm256_sub_ps(_mm256_loadu_ps(y + i), _mm256_mul_ps(LoadHalves(a + i), c8)));
    for (; i < n; ++i) y[i] = y[i] - _cvtsh_ss(a[i]) * c;
  }

  static float Dot(const std::uint16_t* a, const float* x, int n) {
    __m256 lanes8 = _mm256_setzero_ps();
    const int n8 = n - n % 8;
    for (int i = 0; i < n8; i += 8)
      lanes8 = _mm256_add_ps(lanes8, _mm256_mul_ps(LoadHalves(a + i), _mm256_loadu_ps(x + i)));
    alignas(32) float lanes[8];
    _mm256_store_ps(lanes, lanes8);
    float sum = lanes[0];
    for (int j = 1; j < 8; ++j) sum += lanes[j];
    for (int i = n8; i < n; ++i) sum += _cvtsh_ss(a[i]) * x[i];
    return sum;
  }
};

}  // namespace

void SolveWithAvx2(const SweepArgs& args) {
  ForwardSweep<Avx2Kernels>(args);
  BackwardSweep<Avx2Kernels>(args);
}

}  // namespace hapsim::fem::half_sweeps

#endif  // defined(__x86_64__)
