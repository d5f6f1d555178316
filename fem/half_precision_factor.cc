#include "fem/half_precision_factor.h"

#if defined(__x86_64__)
#include <cpuid.h>
#endif

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "fem/half_precision_sweeps.h"

namespace hapsim::fem {
namespace {

using half_sweeps::HalfToFloat;

// The kernels of fem/half_precision_sweeps.h in plain loops, in the order the AVX2 ones use.
struct PortableKernels {
  static float ToFloat(std::uint16_t h) { return HalfToFloat(h); }

  template <int m>
  static void SubtractColumns(const std::uint16_t* a, long lda, const float* c, float* z, int n) {
    for (int i = 0; i < n; ++i) {
      float value = z[i];
      for (int k = 0; k < m; ++k) value = value - HalfToFloat(a[k * lda + i]) * c[k];
      z[i] = value;
    }
  }

  template <int m>
  static void DotColumns(const std::uint16_t* a, long lda, const float* x, int n, float* dots) {
    const int n8 = n - n % 8;
    for (int k = 0; k < m; ++k) {
      const std::uint16_t* column = a + k * lda;
      float lanes[8] = {};
      for (int i = 0; i < n8; i += 8)
        for (int j = 0; j < 8; ++j) lanes[j] = lanes[j] + HalfToFloat(column[i + j]) * x[i + j];
      float sum = lanes[0];
      for (int j = 1; j < 8; ++j) sum += lanes[j];
      for (int i = n8; i < n; ++i) sum += HalfToFloat(column[i]) * x[i];
      dots[k] = sum;
    }
  }
};

// Round to nearest binary16 (ties to even), as bits. |value| ≤ 2¹⁴ here, so never infinite. (The
// entry was rounded to float first: a second rounding, at most 2⁻²⁴ relative, beside 2⁻¹¹.)
std::uint16_t FloatToHalf(float value) {
  return Eigen::half_impl::raw_half_as_uint16(Eigen::half(value));
}

}  // namespace

bool HalfPrecisionFactor::CpuHasVectorKernels() {
#if defined(__x86_64__)
  // AVX2 through the compiler's check (which also asks the OS for the AVX state); F16C from
  // CPUID leaf 1 (ECX bit 29) directly, since clang 14's __builtin_cpu_supports has no "f16c".
  static const bool has = [] {
    unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
    return __builtin_cpu_supports("avx2") && __get_cpuid(1, &eax, &ebx, &ecx, &edx) != 0 &&
           (ecx & bit_F16C) != 0;
  }();
  return has;
#else
  return false;
#endif
}

void HalfPrecisionFactor::Assign(const cholmod_factor& L) {
  layout_.Assign(L);
  const double* x = static_cast<const double*>(L.x);
  double largest = 0.0;
  for (size_t k = 0; k < L.xsize; ++k) largest = std::max(largest, std::abs(x[k]));
  // s = 2^(14 − e) with largest < 2^e: the largest scaled entry lies in [2¹³, 2¹⁴).
  int exponent = 0;
  std::frexp(largest, &exponent);
  scale_ = largest > 0.0 ? std::ldexp(1.0, 14 - exponent) : 1.0;
  values_.resize(L.xsize);
  ConvertToHalf(x, scale_, static_cast<long>(L.xsize), values_.data());
  const int n = layout_.size();
  inverse_diagonal_.resize(n);
  for (int sn = 0; sn < layout_.num_supernodes(); ++sn)
    for (int c = 0; c < layout_.num_columns(sn); ++c)
      inverse_diagonal_[layout_.first_column(sn) + c] = static_cast<float>(
          1.0 / (scale_ * x[layout_.px[sn] + static_cast<long>(c) * layout_.num_rows(sn) + c]));
  y_.resize(n);
  scratch_.resize(std::max(layout_.max_rows, 1));
}

void HalfPrecisionFactor::ConvertToHalf(const double* x, double scale, long n, std::uint16_t* out,
                                        Kernels kernels) {
#if defined(__x86_64__)
  if (kernels == Kernels::kFastest && CpuHasVectorKernels())
    return half_sweeps::ConvertToHalfWithAvx2(x, scale, n, out);
#endif
  for (long k = 0; k < n; ++k) out[k] = FloatToHalf(static_cast<float>(scale * x[k]));
}

void HalfPrecisionFactor::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x,
                                Kernels kernels) const {
  const SupernodalLayout& l = layout_;
  const int n = l.size();
  for (int k = 0; k < n; ++k) y_[k] = static_cast<float>(b[l.perm[k]]);  // y = P b
  const half_sweeps::SweepArgs args{
      l.num_supernodes(), l.super.data(),           l.pi.data(), l.px.data(),    l.s.data(),
      values_.data(),     inverse_diagonal_.data(), y_.data(),   scratch_.data()};
#if defined(__x86_64__)
  if (kernels == Kernels::kFastest && CpuHasVectorKernels()) {
    half_sweeps::SolveWithAvx2(args);
  } else
#endif
  {
    half_sweeps::ForwardSweep<PortableKernels>(args);
    half_sweeps::BackwardSweep<PortableKernels>(args);
  }
  // (sL)⁻ᵀ (sL)⁻¹ = L⁻ᵀ L⁻¹ / s²; s is a power of two, so this is exact.
  const double unscale = scale_ * scale_;
  x->resize(n);
  for (int k = 0; k < n; ++k) (*x)[l.perm[k]] = unscale * y_[k];  // x = Pᵀ y
}

}  // namespace hapsim::fem
