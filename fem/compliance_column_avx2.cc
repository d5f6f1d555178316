// compliance_column::Accumulate with AVX2 intrinsics (fem/compliance_column_kernels.h). This file
// alone is built with -mavx2 (fem/CMakeLists.txt) and is called only on a CPU that has it. It
// includes only <immintrin.h> and the kernels' header, and uses no inline function with external
// linkage (no Eigen, no standard containers), so that no AVX2 copy of one is emitted to replace
// another file's. Keep it so.
#if defined(__x86_64__)

#include <immintrin.h>

#include "fem/compliance_column_kernels.h"

namespace hapsim::fem::compliance_column {

void AccumulateAvx2(const double* C, long ld, long n, const Entry* entries, int count, double* q) {
  for (long i = 0; i < n; ++i) q[i] = 0.0;
  for (int e = 0; e < count; ++e) {
    const Entry& a = entries[e];
    const double* c0 = C + a.block * ld;
    const double* c1 = c0 + ld;
    const double* c2 = c1 + ld;
    const __m256d g0 = _mm256_set1_pd(a.g0), g1 = _mm256_set1_pd(a.g1), g2 = _mm256_set1_pd(a.g2);
    long i = 0;
    for (; i + 4 <= n; i += 4) {
      const __m256d pair = _mm256_add_pd(_mm256_mul_pd(g0, _mm256_loadu_pd(c0 + i)),
                                         _mm256_mul_pd(g1, _mm256_loadu_pd(c1 + i)));
      const __m256d term = _mm256_add_pd(pair, _mm256_mul_pd(g2, _mm256_loadu_pd(c2 + i)));
      _mm256_storeu_pd(q + i, _mm256_add_pd(_mm256_loadu_pd(q + i), term));
    }
    for (; i < n; ++i) q[i] = q[i] + ((a.g0 * c0[i] + a.g1 * c1[i]) + a.g2 * c2[i]);
  }
}

}  // namespace hapsim::fem::compliance_column

#endif  // __x86_64__
