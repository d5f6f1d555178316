#pragma once
// q = C Uᵀ e_c, the product that forms a column of the warped compliance's W
// (WarpedCompliance::MultiplyRowByCompliance), over raw pointers: a portable loop here and the
// same loop in AVX2 intrinsics in a file of its own, built for that instruction set
// (compliance_column_avx2.cc, called only where SinglePrecisionFactor::CpuHasVectorKernels).
// Both compute every q[i] by the same operations in the same order, without fused multiply-add,
// so they give the same bits: q[i] ← q[i] + ((g0 C(i, b) + g1 C(i, b + 1)) + g2 C(i, b + 2)) for
// each entry in turn, from q = 0. (That is also the order Eigen evaluated the column expression
// that the loop replaced, so W is bit for bit what it was.) Four doubles an instruction instead
// of SSE2's two: block_press's 140 columns a frame, ~0.2 µs a column less (docs/BENCHMARKS.md,
// eighth pass).
//
// As with the float sweeps (fem/float_column_sweeps.h), the portable function has internal
// linkage, so that no AVX2 copy of it can stand in for it.

namespace hapsim::fem::compliance_column {

// One entry of a row of U: its weights at one node and the node's first column in C.
struct Entry {
  int block;
  double g0, g1, g2;
};

// q[0 .. n) = Σ over entries[0 .. count) as above; C column-major with leading dimension ld.
static inline void Accumulate(const double* C, long ld, long n, const Entry* entries, int count,
                              double* q) {
  for (long i = 0; i < n; ++i) q[i] = 0.0;
  for (int e = 0; e < count; ++e) {
    const Entry& a = entries[e];
    const double* c0 = C + a.block * ld;
    const double* c1 = c0 + ld;
    const double* c2 = c1 + ld;
    for (long i = 0; i < n; ++i) q[i] = q[i] + ((a.g0 * c0[i] + a.g1 * c1[i]) + a.g2 * c2[i]);
  }
}

// The same with AVX2; call only on a CPU that has it.
void AccumulateAvx2(const double* C, long ld, long n, const Entry* entries, int count, double* q);

}  // namespace hapsim::fem::compliance_column
