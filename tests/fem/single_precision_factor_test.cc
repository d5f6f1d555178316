// The reduced-precision copies of a CHOLMOD factor against a dense solve of the same system matrix
// (a second method): the float copy (fem/single_precision_factor.h) equal to float accuracy, the
// binary16 one (fem/half_precision_factor.h) to binary16 accuracy, each far from exact, which
// shows it really is that path. And the binary16 copy's scaling, kernels and allocations.
#include <dirent.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <thread>

#include "fem/cholmod_factor.h"
#include "fem/half_precision_factor.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/time_stepper.h"
#include "tests/allocation_counter.h"

namespace hapsim::fem {
namespace {

// A block fixed at its base, 8 x 8 x 4 cells (405 nodes): large enough for a factor of many
// supernodes, most with rows below their diagonal blocks.
Eigen::SparseMatrix<double> MakeSystemMatrix() {
  const TetMesh mesh = MakeBoxTetMesh({0, 0, 0}, {0.04, 0.04, 0.02}, {8, 8, 4});
  Material material;
  material.youngs_modulus_Pa = 5e4;
  material.rayleigh_beta_s = 0.01;
  const Model model =
      MakeModel(mesh, material, FindNodesInBox(mesh, {-1, -1, -1}, {1, 1, 1e-9}, 0.0));
  const TimeStepper stepper(model, FemOptions{}, 1.0 / 60.0,
                            Eigen::VectorXd::Zero(model.num_dofs()));
  return stepper.MakeRestSystemMatrix();
}

// The whole symmetric matrix of which A holds the lower triangle.
Eigen::MatrixXd Dense(const Eigen::SparseMatrix<double>& A) {
  return Eigen::MatrixXd(Eigen::SparseMatrix<double>(A.selfadjointView<Eigen::Lower>()));
}

// κ(A) = λ_max / λ_min of a symmetric positive definite A.
double ConditionNumber(const Eigen::MatrixXd& A) {
  const Eigen::VectorXd eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A, Eigen::EigenvaluesOnly).eigenvalues();
  return eigenvalues.maxCoeff() / eigenvalues.minCoeff();
}

TEST(SinglePrecisionFactor, SolvesToFloatAccuracyAgainstADenseSolve) {
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  const Eigen::MatrixXd A_dense = Dense(A);
  const Eigen::LDLT<Eigen::MatrixXd> dense(A_dense);
  const double condition = ConditionNumber(A_dense);
  CholmodFactor factor;
  factor.KeepCopy(FactorPrecision::kSingle);
  ASSERT_TRUE(factor.Factorize(A));
  srand(3);
  double worst_single = 0.0, worst_double = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd b = Eigen::VectorXd::Random(A.rows());
    const Eigen::VectorXd x_reference = dense.solve(b);
    Eigen::VectorXd x_single, x_double;
    factor.SolveWithCopy(b, &x_single);
    factor.Solve(b, &x_double);
    worst_single = std::max(worst_single, (x_single - x_reference).norm() / x_reference.norm());
    worst_double = std::max(worst_double, (x_double - x_reference).norm() / x_reference.norm());
  }
  std::printf(
      "n %ld, factor nonzeros %.0f, condition %.2e: relative error single %.2e, double "
      "%.2e\n",
      static_cast<long>(A.rows()), factor.num_factor_nonzeros(), condition, worst_single,
      worst_double);
  // Rounding L to float perturbs it by ε_f = 6e-8 relative; the solve's error is then at most of
  // order ε_f · κ(A) (Higham, Accuracy and Stability, §10.1): 4.7e-5 here, measured 2.1e-7.
  EXPECT_LE(worst_single, 6e-8 * condition);
  EXPECT_GT(worst_single, 100.0 * worst_double);  // it is the float path, not the double one
  EXPECT_LE(worst_double, 1e-12 * condition);
}

// Several columns at once with the float copy, against the dense solve, each to float accuracy as
// SolveWithCopy is: the columns of the identity of two free nodes far apart (the forward
// sweep skips the supernodes where all six are still zero, and must not skip one where only some
// are: the two nodes' elimination-tree paths differ until they meet), and dense columns (it
// skips none).
TEST(SinglePrecisionFactor, SolvesSeveralColumnsAtOnce) {
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  const Eigen::MatrixXd A_dense = Dense(A);
  const double condition = ConditionNumber(A_dense);
  CholmodFactor factor;
  factor.KeepCopy(FactorPrecision::kSingle);
  ASSERT_TRUE(factor.Factorize(A));
  const int num_nodes = static_cast<int>(A.rows() / 3);
  Eigen::MatrixXd identity_columns = Eigen::MatrixXd::Zero(A.rows(), 6);
  for (int k = 0; k < 2; ++k)
    for (int d = 0; d < 3; ++d)
      identity_columns(3 * (k == 0 ? num_nodes / 2 : num_nodes - 1) + d, 3 * k + d) = 1.0;
  srand(9);
  const Eigen::MatrixXd dense_columns = Eigen::MatrixXd::Random(A.rows(), 2);
  const Eigen::LDLT<Eigen::MatrixXd> dense(A_dense);
  for (const Eigen::MatrixXd& B : {identity_columns, dense_columns}) {
    const Eigen::MatrixXd X = factor.SolveColumnsWithCopy(B);
    const Eigen::MatrixXd X_reference = dense.solve(B);
    for (Eigen::Index c = 0; c < B.cols(); ++c) {
      const double error = (X.col(c) - X_reference.col(c)).norm() / X_reference.col(c).norm();
      EXPECT_LE(error, 6e-8 * condition) << B.cols() << " columns, column " << c;
      EXPECT_GT(error, 0.0) << "column " << c << ": float, so not exact";
    }
  }
}

// Columns wanted at a few rows only: the backward sweep skips the supernodes off those rows'
// elimination-tree paths; at the wanted rows it gives what the whole solve gives, bit for bit (a
// backward step reads only its ancestors' rows).
TEST(SinglePrecisionFactor, SolvesColumnsAtWantedRowsOnly) {
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  CholmodFactor factor;
  factor.KeepCopy(FactorPrecision::kSingle);
  ASSERT_TRUE(factor.Factorize(A));
  const int num_nodes = static_cast<int>(A.rows() / 3);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(A.rows(), 3);
  for (int d = 0; d < 3; ++d) B(3 * (num_nodes - 1) + d, d) = 1.0;  // a top corner node
  const std::vector<int> wanted_rows = {3 * (num_nodes - 1), 3 * (num_nodes - 1) + 2,
                                        3 * (num_nodes - 2) + 1, 3 * (num_nodes / 2), 0};
  const Eigen::MatrixXd X_all = factor.SolveColumnsWithCopy(B);
  const Eigen::MatrixXd X = factor.SolveColumnsWithCopyAt(B, wanted_rows);
  ASSERT_EQ(X.rows(), static_cast<Eigen::Index>(wanted_rows.size()));
  for (size_t i = 0; i < wanted_rows.size(); ++i)
    EXPECT_EQ(X.row(i), X_all.row(wanted_rows[i])) << "row " << wanted_rows[i];
}

// The multi-column sweeps' AVX2 kernels and the portable ones subtract in the same order without
// fused multiply-adds: the same bits, for 6 columns (padded to 8) and for 40 (chunks of 24 and 16).
TEST(SinglePrecisionFactor, ColumnKernelsEqualPortableOnesBitForBit) {
  if (!SinglePrecisionFactor::CpuHasVectorKernels()) GTEST_SKIP() << "this CPU lacks AVX2";
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  CholmodFactor factor;
  factor.KeepCopy(FactorPrecision::kSingle);
  ASSERT_TRUE(factor.Factorize(A));
  const SinglePrecisionFactor& copy = factor.single_precision_copy();
  srand(13);
  const std::vector<int> wanted_rows = {0, 7, static_cast<int>(A.rows()) - 1};
  for (const int columns : {6, 40}) {
    const Eigen::MatrixXd B = Eigen::MatrixXd::Random(A.rows(), columns);
    EXPECT_EQ(copy.SolveColumns(B, SinglePrecisionFactor::Kernels::kFastest),
              copy.SolveColumns(B, SinglePrecisionFactor::Kernels::kPortable))
        << columns << " columns";
    EXPECT_EQ(copy.SolveColumnsAt(B, wanted_rows, SinglePrecisionFactor::Kernels::kFastest),
              copy.SolveColumnsAt(B, wanted_rows, SinglePrecisionFactor::Kernels::kPortable))
        << columns << " columns";
  }
}

// The worst relative error of factor.SolveWithCopy over five random right-hand sides, against a
// dense LDLᵀ solve of A.
double WorstCopyError(const Eigen::SparseMatrix<double>& A, const CholmodFactor& factor) {
  const Eigen::LDLT<Eigen::MatrixXd> dense(Dense(A));
  srand(5);
  double worst = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd b = Eigen::VectorXd::Random(A.rows());
    const Eigen::VectorXd x_reference = dense.solve(b);
    Eigen::VectorXd x;
    factor.SolveWithCopy(b, &x);
    worst = std::max(worst, (x - x_reference).norm() / x_reference.norm());
  }
  return worst;
}

TEST(HalfPrecisionFactor, SolvesToHalfAccuracyAgainstADenseSolve) {
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  CholmodFactor half, single;
  half.KeepCopy(FactorPrecision::kHalf);
  single.KeepCopy(FactorPrecision::kSingle);
  ASSERT_TRUE(half.Factorize(A));
  ASSERT_TRUE(single.Factorize(A));
  const double worst_half = WorstCopyError(A, half), worst_single = WorstCopyError(A, single);
  std::printf("relative error: binary16 %.2e, float %.2e\n", worst_half, worst_single);
  // Rounding L to binary16 perturbs it by 2⁻¹¹ = 4.9e-4 relative; the solve's error is then at
  // most of order that times κ(A) (Higham, as for the float copy): 0.38 here, measured 2.6e-4.
  // Loose, as that bound is; the float copy's error, 8192 times smaller in ε, shows it is the
  // binary16 path and not the float one.
  EXPECT_LE(worst_half, 4.9e-4 * ConditionNumber(Dense(A)));
  EXPECT_GT(worst_half, 100.0 * worst_single);
}

// L is stored scaled by a power of two s (its largest entry near 2¹⁴). For A·2⁻⁴⁰, L is L·2⁻²⁰,
// s grows by 2²⁰, so the stored entries are the same and A⁻¹ b must be exactly 2⁴⁰ times as large:
// bit for bit. Unscaled, entries near 1e-6·2⁻²⁰ would be binary16 subnormals or zero.
TEST(HalfPrecisionFactor, ScalingIsExactForAnyMagnitude) {
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  const Eigen::SparseMatrix<double> A_tiny = A * std::ldexp(1.0, -40);
  CholmodFactor factor, factor_tiny;
  factor.KeepCopy(FactorPrecision::kHalf);
  factor_tiny.KeepCopy(FactorPrecision::kHalf);
  ASSERT_TRUE(factor.Factorize(A));
  ASSERT_TRUE(factor_tiny.Factorize(A_tiny));
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(A.rows(), -1.0, 2.0);
  Eigen::VectorXd x, x_tiny;
  factor.SolveWithCopy(b, &x);
  factor_tiny.SolveWithCopy(b, &x_tiny);
  ASSERT_TRUE(x.allFinite());
  EXPECT_EQ(x_tiny, std::ldexp(1.0, 40) * x);
}

// The AVX2 + F16C kernels and the portable ones add in the same order without fused
// multiply-adds: the same bits on every CPU.
TEST(HalfPrecisionFactor, VectorKernelsEqualPortableOnesBitForBit) {
  if (!HalfPrecisionFactor::CpuHasVectorKernels()) GTEST_SKIP() << "this CPU lacks AVX2 or F16C";
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  CholmodFactor factor;
  factor.KeepCopy(FactorPrecision::kHalf);
  ASSERT_TRUE(factor.Factorize(A));
  const HalfPrecisionFactor& copy = factor.half_precision_copy();
  srand(11);
  for (int trial = 0; trial < 3; ++trial) {
    const Eigen::VectorXd b = Eigen::VectorXd::Random(A.rows());
    Eigen::VectorXd x_vector, x_portable;
    copy.Solve(b, &x_vector, HalfPrecisionFactor::Kernels::kFastest);
    copy.Solve(b, &x_portable, HalfPrecisionFactor::Kernels::kPortable);
    EXPECT_EQ(x_vector, x_portable) << "trial " << trial;
  }
}

// Assign's conversion to binary16, against IEEE values worked by hand (ties go to the even
// neighbour, the smallest subnormal, the largest finite), and the F16C path against the portable
// one bit for bit over many magnitudes, with a tail that is not a multiple of eight.
TEST(HalfPrecisionFactor, ConvertsToHalfByRoundingToNearestEven) {
  const std::vector<std::pair<double, std::uint16_t>> known = {
      {1.0, 0x3c00},                         // 1
      {1.0 + std::ldexp(1.0, -11), 0x3c00},  // halfway between 1 and 1 + 2⁻¹⁰: to the even 1
      {1.0 + 3 * std::ldexp(1.0, -11), 0x3c02},  // halfway, to the even 1 + 2⁻⁹
      {-2.5, 0xc100},
      {std::ldexp(1.0, -24), 0x0001},  // the smallest subnormal
      {65504.0, 0x7bff}};              // the largest finite
  // All in one call, twelve entries: the vector path converts the first eight at once.
  std::vector<double> values;
  std::vector<std::uint16_t> expected;
  for (int copy = 0; copy < 2; ++copy)
    for (const auto& [value, bits] : known) values.push_back(value), expected.push_back(bits);
  for (const auto kernels :
       {HalfPrecisionFactor::Kernels::kPortable, HalfPrecisionFactor::Kernels::kFastest}) {
    std::vector<std::uint16_t> out(values.size());
    HalfPrecisionFactor::ConvertToHalf(values.data(), 1.0, static_cast<long>(values.size()),
                                       out.data(), kernels);
    EXPECT_EQ(out, expected) << (kernels == HalfPrecisionFactor::Kernels::kPortable ? "portable"
                                                                                    : "fastest");
  }
  if (!HalfPrecisionFactor::CpuHasVectorKernels()) GTEST_SKIP() << "this CPU lacks AVX2 or F16C";
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-30, 14);
  std::vector<double> x(1003);
  for (double& value : x) value = std::ldexp(mantissa(rng), exponent(rng));
  std::vector<std::uint16_t> vector(x.size()), portable(x.size());
  HalfPrecisionFactor::ConvertToHalf(x.data(), 0.5, static_cast<long>(x.size()), vector.data(),
                                     HalfPrecisionFactor::Kernels::kFastest);
  HalfPrecisionFactor::ConvertToHalf(x.data(), 0.5, static_cast<long>(x.size()), portable.data(),
                                     HalfPrecisionFactor::Kernels::kPortable);
  EXPECT_EQ(vector, portable);
}

TEST(HalfPrecisionFactor, SolveAllocatesNothingOnceSized) {
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations are not counted here";
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  CholmodFactor factor;
  factor.KeepCopy(FactorPrecision::kHalf);
  ASSERT_TRUE(factor.Factorize(A));
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(A.rows());
  Eigen::VectorXd x;
  factor.SolveWithCopy(b, &x);
  AllocationCounter counter;
  factor.SolveWithCopy(b, &x);
  EXPECT_EQ(counter.count(), 0);
}

TEST(SinglePrecisionFactor, RefusedWithoutACopy) {
  CholmodFactor factor;
  ASSERT_TRUE(factor.Factorize(MakeSystemMatrix()));
  Eigen::VectorXd x;
  EXPECT_THROW(factor.SolveWithCopy(Eigen::VectorXd::Ones(3), &x), std::logic_error);
}

// Threads of this process, from /proc/self/task.
int CountThreads() {
  DIR* tasks = opendir("/proc/self/task");
  if (!tasks) return -1;
  int count = 0;
  while (const dirent* entry = readdir(tasks))
    if (entry->d_name[0] != '.') ++count;
  closedir(tasks);
  return count;
}

// Debian's CHOLMOD asks for 4 OpenMP threads inside its supernodal factorisation; CholmodFactor
// keeps it on the calling thread (fem/cholmod_factor.cc). libgomp keeps the threads it starts in a
// pool of the thread that started them, so the factorisation runs on a thread of its own (an
// earlier test on the main thread cannot have filled that pool), and the process must have as
// many threads after it as while it began (one for gtest, that one, and any a sanitizer adds).
TEST(CholmodFactor, FactorisesOnTheCallingThreadOnly) {
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  int threads_at_start = 0, threads_at_end = 0;
  bool factored = false;
  std::thread worker([&] {
    threads_at_start = CountThreads();
    CholmodFactor factor;
    factored = factor.Factorize(A);
    Eigen::VectorXd x;
    if (factored) factor.Solve(Eigen::VectorXd::Ones(A.rows()), &x);
    threads_at_end = CountThreads();
  });
  worker.join();
  ASSERT_TRUE(factored);
  ASSERT_GE(threads_at_start, 2);
  EXPECT_EQ(threads_at_end, threads_at_start);
}

}  // namespace
}  // namespace hapsim::fem
