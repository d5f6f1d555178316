// The single-precision copy of a CHOLMOD factor (fem/single_precision_factor.h) against a dense
// solve of the same system matrix (a second method): equal to float accuracy, i.e. far closer
// than a preconditioner needs and far from exact, which shows it really is the float path.
#include <dirent.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "fem/cholmod_factor.h"
#include "fem/lattice_mesher.h"
#include "fem/model.h"
#include "fem/time_stepper.h"

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

TEST(SinglePrecisionFactor, SolvesToFloatAccuracyAgainstADenseSolve) {
  const Eigen::SparseMatrix<double> A = MakeSystemMatrix();
  const Eigen::MatrixXd A_dense =
      Eigen::MatrixXd(Eigen::SparseMatrix<double>(A.selfadjointView<Eigen::Lower>()));
  const Eigen::LDLT<Eigen::MatrixXd> dense(A_dense);
  const Eigen::VectorXd eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(A_dense, Eigen::EigenvaluesOnly).eigenvalues();
  const double condition = eigenvalues.maxCoeff() / eigenvalues.minCoeff();
  CholmodFactor factor;
  factor.KeepSinglePrecisionCopy();
  ASSERT_TRUE(factor.Factorize(A));
  srand(3);
  double worst_single = 0.0, worst_double = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd b = Eigen::VectorXd::Random(A.rows());
    const Eigen::VectorXd x_reference = dense.solve(b);
    Eigen::VectorXd x_single, x_double;
    factor.SolveSinglePrecision(b, &x_single);
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

TEST(SinglePrecisionFactor, RefusedWithoutACopy) {
  CholmodFactor factor;
  ASSERT_TRUE(factor.Factorize(MakeSystemMatrix()));
  Eigen::VectorXd x;
  EXPECT_THROW(factor.SolveSinglePrecision(Eigen::VectorXd::Ones(3), &x), std::logic_error);
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
