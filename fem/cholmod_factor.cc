#include "fem/cholmod_factor.h"

#include <stdexcept>
#include <vector>

#include "fem/inverse_quadratic_form.h"

// The one OpenMP routine used, from libgomp, the runtime Debian's CHOLMOD is built against (linked
// in fem/CMakeLists.txt). Declared here rather than through <omp.h>: clang does not search GCC's
// private include directory, and LLVM's omp.h is another package.
extern "C" void omp_set_max_active_levels(int max_levels);

namespace hapsim::fem {
namespace {

// Debian's CHOLMOD is built with OpenMP and asks for CHOLMOD_OMP_NUM_THREADS = 4 threads (a
// compile-time constant in a num_threads clause, which OMP_NUM_THREADS does not override) in the
// supernodal factorisation's scatter loops. On this 2-core machine, with a one-thread job on the
// other core as the haptic process would be, those threads mostly wait on each other: a
// factorisation took 12.0 ms wall for 6.7 ms of the calling thread's CPU at 3.6k tets, and 178 ms
// for 118 ms at 28.8k (a hand run before this setting, 2026-11-26: no command reproduces it now);
// on the calling thread alone it takes 4.9 and 108 ms (BM_Factorize regenerates those). The
// threads also took CPU from that other job. With no active parallel level allowed, every
// OpenMP region runs on the calling thread. The setting belongs to the calling thread, so it is
// made before each call into CHOLMOD, not once.
void KeepCholmodOnCallingThread() { omp_set_max_active_levels(0); }

// A CHOLMOD view (no copy) of a compressed column-major symmetric matrix, reading its lower half.
cholmod_sparse ViewAsCholmod(const Eigen::SparseMatrix<double>& A) {
  cholmod_sparse view{};
  view.nrow = static_cast<size_t>(A.rows());
  view.ncol = static_cast<size_t>(A.cols());
  view.nzmax = static_cast<size_t>(A.nonZeros());
  view.p = const_cast<int*>(A.outerIndexPtr());
  view.i = const_cast<int*>(A.innerIndexPtr());
  view.x = const_cast<double*>(A.valuePtr());
  view.stype = -1;
  view.itype = CHOLMOD_INT;
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  view.sorted = 1;
  view.packed = 1;
  return view;
}

// A CHOLMOD view (no copy) of a dense column-major matrix or vector.
cholmod_dense ViewAsCholmod(const Eigen::Ref<const Eigen::MatrixXd>& b) {
  cholmod_dense view{};
  view.nrow = static_cast<size_t>(b.rows());
  view.ncol = static_cast<size_t>(b.cols());
  view.nzmax = static_cast<size_t>(b.size());
  view.d = static_cast<size_t>(b.outerStride());
  view.x = const_cast<double*>(b.data());
  view.xtype = CHOLMOD_REAL;
  view.dtype = CHOLMOD_DOUBLE;
  return view;
}

}  // namespace

CholmodFactor::CholmodFactor() {
  cholmod_start(&common_);
  common_.supernodal = CHOLMOD_SUPERNODAL;
  common_.final_asis = 1;  // keep the factor supernodal: the solves work on it directly
  common_.print = 0;
  // Nested dissection (METIS, then CAMD within each part): on the 28.8k-tet block L has 4.08 M
  // nonzeros against 4.30 M with CHOLMOD's default choice (METIS) and 4.95 M with AMD, and a
  // solve is 7% faster; on the 3.6k-tet block the three are within 3%. Measured 2026-11-25.
  common_.nmethods = 1;
  common_.method[0].ordering = CHOLMOD_NESDIS;
}

CholmodFactor::~CholmodFactor() {
  cholmod_free_dense(&solution_, &common_);
  cholmod_free_dense(&work_y_, &common_);
  cholmod_free_dense(&work_e_, &common_);
  cholmod_free_factor(&factor_, &common_);
  cholmod_finish(&common_);
}

void CholmodFactor::Analyze(const Eigen::SparseMatrix<double>& A) {
  if (!A.isCompressed()) throw std::invalid_argument("CholmodFactor needs a compressed matrix");
  if (factor_ && A.nonZeros() == analysed_nonzeros_) return;
  cholmod_sparse A_view = ViewAsCholmod(A);
  KeepCholmodOnCallingThread();
  cholmod_free_factor(&factor_, &common_);
  factored_ = false;
  factor_ = cholmod_analyze(&A_view, &common_);
  if (!factor_) throw std::runtime_error("CHOLMOD symbolic analysis failed");
  analysed_nonzeros_ = A.nonZeros();
  layout_ = SupernodalLayout();  // a new structure: read again once factored
}

bool CholmodFactor::Factorize(const Eigen::SparseMatrix<double>& A) {
  Analyze(A);
  cholmod_sparse A_view = ViewAsCholmod(A);
  KeepCholmodOnCallingThread();
  cholmod_factorize(&A_view, factor_, &common_);
  if (common_.status == CHOLMOD_OUT_OF_MEMORY) throw std::runtime_error("CHOLMOD out of memory");
  factored_ = common_.status == CHOLMOD_OK;
  if (factored_ && copy_precision_ == FactorPrecision::kSingle) single_.Assign(*factor_);
  if (factored_ && copy_precision_ == FactorPrecision::kHalf) half_.Assign(*factor_);
  return factored_;
}

void CholmodFactor::SolveWithCopy(const Eigen::VectorXd& b, Eigen::VectorXd* x) const {
  if (factored_ && copy_precision_ == FactorPrecision::kSingle && !single_.empty())
    return single_.Solve(b, x);
  if (factored_ && copy_precision_ == FactorPrecision::kHalf && !half_.empty())
    return half_.Solve(b, x);
  throw std::logic_error("CholmodFactor::SolveWithCopy without a reduced-precision copy");
}

void CholmodFactor::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) {
  if (!factored_) throw std::logic_error("CholmodFactor::Solve before a successful Factorize");
  cholmod_dense b_view = ViewAsCholmod(b);
  KeepCholmodOnCallingThread();
  if (!cholmod_solve2(CHOLMOD_A, factor_, &b_view, nullptr, &solution_, nullptr, &work_y_, &work_e_,
                      &common_))
    throw std::runtime_error("CHOLMOD solve failed");
  *x = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(solution_->x), b.size());
}

Eigen::MatrixXd CholmodFactor::SolveColumns(const Eigen::MatrixXd& B) {
  if (!factored_)
    throw std::logic_error("CholmodFactor::SolveColumns before a successful Factorize");
  cholmod_dense B_view = ViewAsCholmod(B);
  KeepCholmodOnCallingThread();
  cholmod_dense* X = cholmod_solve(CHOLMOD_A, factor_, &B_view, &common_);
  if (!X) throw std::runtime_error("CHOLMOD solve failed");
  Eigen::MatrixXd result =
      Eigen::Map<const Eigen::MatrixXd>(static_cast<const double*>(X->x), B.rows(), B.cols());
  cholmod_free_dense(&X, &common_);
  return result;
}

Eigen::MatrixXd CholmodFactor::SolveColumnsWithCopy(const Eigen::MatrixXd& B) const {
  if (!factored_ || copy_precision_ != FactorPrecision::kSingle || single_.empty())
    throw std::logic_error("CholmodFactor::SolveColumnsWithCopy without a float copy");
  return single_.SolveColumns(B);
}

Eigen::MatrixXd CholmodFactor::SolveColumnsWithCopyAt(const Eigen::MatrixXd& B,
                                                      const std::vector<int>& wanted_rows) const {
  if (!factored_ || copy_precision_ != FactorPrecision::kSingle || single_.empty())
    throw std::logic_error("CholmodFactor::SolveColumnsWithCopyAt without a float copy");
  return single_.SolveColumnsAt(B, wanted_rows);
}

Eigen::MatrixXd CholmodFactor::CalcInverseQuadraticForm(const Eigen::SparseMatrix<double>& J) {
  if (!factored_) throw std::logic_error("CholmodFactor: no factor");
  // The structure is the symbolic analysis's, which numeric factorisations keep (final_asis).
  if (layout_.empty()) layout_.Assign(*factor_);
  return fem::CalcInverseQuadraticForm(layout_, static_cast<const double*>(factor_->x), J);
}

}  // namespace hapsim::fem
