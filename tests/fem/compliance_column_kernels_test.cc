// The kernels of a warped-compliance column, q = C Uᵀ e_c (fem/compliance_column_kernels.h): the
// AVX2 one gives the portable one's bits, and both give the dense product C (Σ_e G_e) to round-off,
// over column lengths that leave 0–3 entries past the last group of four. (Built, as the kernels
// are, without contraction into fused multiply-adds: tests/CMakeLists.txt.)

#include "fem/compliance_column_kernels.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>
#include <vector>

#include "fem/single_precision_factor.h"

namespace hapsim::fem {
namespace {

struct Case {
  Eigen::MatrixXd C;  // leading dimension larger than the rows used, as a held block's is
  long n;
  std::vector<compliance_column::Entry> entries;
};

Case MakeCase(long n, int count, std::mt19937* random) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Case c;
  c.n = n;
  c.C = Eigen::MatrixXd::NullaryExpr(n + 5, n, [&] { return unit(*random); });
  std::uniform_int_distribution<int> block(0, static_cast<int>(n / 3) - 1);
  for (int e = 0; e < count; ++e)
    c.entries.push_back({3 * block(*random), unit(*random), unit(*random), unit(*random)});
  return c;
}

TEST(ComplianceColumnKernels, PortableIsTheDenseProduct) {
  std::mt19937 random(3);
  for (long n : {3L, 6L, 9L, 12L, 354L, 355L, 357L}) {
    const Case c = MakeCase(n, 5, &random);
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n);  // Uᵀ e_c over C's columns
    for (const compliance_column::Entry& a : c.entries)
      u.segment<3>(a.block) += Eigen::Vector3d(a.g0, a.g1, a.g2);
    const Eigen::VectorXd expected = c.C.topRows(n) * u;
    Eigen::VectorXd q(n);
    compliance_column::Accumulate(c.C.data(), c.C.outerStride(), n, c.entries.data(),
                                  static_cast<int>(c.entries.size()), q.data());
    EXPECT_LT((q - expected).lpNorm<Eigen::Infinity>(), 1e-13 * (1.0 + expected.norm()))
        << "n " << n;
  }
}

#if defined(__x86_64__)  // the AVX2 kernel is built there only
TEST(ComplianceColumnKernels, Avx2GivesThePortableBits) {
  if (!SinglePrecisionFactor::CpuHasVectorKernels()) GTEST_SKIP() << "this CPU lacks AVX2";
  std::mt19937 random(5);
  for (long n : {3L, 6L, 9L, 12L, 354L, 355L, 357L}) {
    for (int count : {0, 1, 3, 9}) {
      const Case c = MakeCase(n, count, &random);
      Eigen::VectorXd portable(n), avx2(n);
      compliance_column::Accumulate(c.C.data(), c.C.outerStride(), n, c.entries.data(), count,
                                    portable.data());
      compliance_column::AccumulateAvx2(c.C.data(), c.C.outerStride(), n, c.entries.data(), count,
                                        avx2.data());
      for (long i = 0; i < n; ++i)
        ASSERT_EQ(portable[i], avx2[i]) << "n " << n << ", entries " << count << ", row " << i;
    }
  }
}
#endif

}  // namespace
}  // namespace hapsim::fem
