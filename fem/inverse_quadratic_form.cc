#include "fem/inverse_quadratic_form.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

// The BLAS that CHOLMOD's supernodal kernels call (Debian: OpenBLAS through libblas.so.3).
extern "C" {
void dgemm_(const char* transa, const char* transb, const int* m, const int* n, const int* k,
            const double* alpha, const double* a, const int* lda, const double* b, const int* ldb,
            const double* beta, double* c, const int* ldc);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m,
            const int* n, const double* alpha, const double* a, const int* lda, double* b,
            const int* ldb);
}

namespace hapsim::fem {
namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// The supernodes on the elimination-tree paths from the dofs' supernodes to the root, ascending
// (a child before its parent, as CHOLMOD numbers them), and each permuted row's index among
// their rows (−1 off them). A supernode's columns get consecutive indices.
struct Reach {
  std::vector<int> supernodes;
  std::vector<int> compact_row;
  int num_rows = 0;
};

Reach FindReach(const SupernodalLayout& l, const std::vector<int>& dofs) {
  std::vector<char> needed(l.num_supernodes(), 0);
  for (int dof : dofs)
    for (int sn = l.supernode_of_column[l.permuted_index[dof]]; sn != -1 && !needed[sn];
         sn = l.parent[sn])
      needed[sn] = 1;
  Reach reach;
  reach.compact_row.assign(l.size(), -1);
  for (int sn = 0; sn < l.num_supernodes(); ++sn) {
    if (!needed[sn]) continue;
    reach.supernodes.push_back(sn);
    for (int k = l.first_column(sn); k < l.first_column(sn) + l.num_columns(sn); ++k)
      reach.compact_row[k] = reach.num_rows++;
  }
  return reach;
}

// Y ← L⁻¹ Y over the reach: per supernode, its diagonal block's triangle, then the rows below it
// (ancestors' columns, in the reach) less that block's product with the solved rows. In BLAS's
// column-major terms the rows of Y are the columns of Yᵀ (c × rows, leading dimension c), so
// Y_s ← L_ss⁻¹ Y_s is Y_sᵀ ← Y_sᵀ L_ssᵀ⁻¹ and the update below is Y_sᵀ L_bsᵀ.
void SolveForward(const SupernodalLayout& l, const double* values, const Reach& reach,
                  RowMatrix* Y, RowMatrix* scratch) {
  const int c = static_cast<int>(Y->cols());
  const double one = 1.0, zero = 0.0;
  for (int sn : reach.supernodes) {
    int cols = l.num_columns(sn), rows = l.num_rows(sn), below = rows - cols;
    const double* block = values + l.px[sn];
    double* Yt_s = Y->row(reach.compact_row[l.first_column(sn)]).data();
    dtrsm_("R", "L", "T", "N", &c, &cols, &one, block, &rows, Yt_s, &c);
    if (below == 0) continue;
    dgemm_("N", "T", &c, &below, &cols, &one, Yt_s, &c, block + cols, &rows, &zero,
           scratch->data(), &c);
    const int* rows_below = l.rows_below(sn);
    for (int i = 0; i < below; ++i)
      Y->row(reach.compact_row[rows_below[i]]) -= scratch->row(i);
  }
}

// Y ← L⁻ᵀ Y over the reach, from the root down (a supernode's rows need only its ancestors'):
// Y_s ← L_ssᵀ⁻¹ (Y_s − L_bsᵀ Y_b), that is Y_sᵀ ← (Y_sᵀ − Y_bᵀ L_bs) L_ss⁻¹.
void SolveBackward(const SupernodalLayout& l, const double* values, const Reach& reach,
                   RowMatrix* Y, RowMatrix* scratch) {
  const int c = static_cast<int>(Y->cols());
  const double one = 1.0, minus_one = -1.0;
  for (auto it = reach.supernodes.rbegin(); it != reach.supernodes.rend(); ++it) {
    const int sn = *it;
    int cols = l.num_columns(sn), rows = l.num_rows(sn), below = rows - cols;
    const double* block = values + l.px[sn];
    double* Yt_s = Y->row(reach.compact_row[l.first_column(sn)]).data();
    if (below > 0) {
      const int* rows_below = l.rows_below(sn);
      for (int i = 0; i < below; ++i) scratch->row(i) = Y->row(reach.compact_row[rows_below[i]]);
      dgemm_("N", "N", &c, &cols, &below, &minus_one, scratch->data(), &c, block + cols, &rows,
             &one, Yt_s, &c);
    }
    dtrsm_("R", "L", "N", "N", &c, &cols, &one, block, &rows, Yt_s, &c);
  }
}

}  // namespace

Eigen::MatrixXd CalcInverseQuadraticForm(const SupernodalLayout& l, const double* L_values,
                                         const Eigen::SparseMatrix<double>& J) {
  if (J.cols() != l.size())
    throw std::invalid_argument("CalcInverseQuadraticForm: J has " + std::to_string(J.cols()) +
                                " columns, the factor " + std::to_string(l.size()) + " rows");
  const Eigen::Index num_rows = J.rows();
  std::vector<int> touched;  // the dofs the contacts move: J's columns with entries
  for (int dof = 0; dof < J.outerSize(); ++dof)
    if (Eigen::SparseMatrix<double>::InnerIterator(J, dof)) touched.push_back(dof);
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(num_rows, num_rows);
  if (touched.empty()) return W;

  const Reach reach = FindReach(l, touched);
  RowMatrix Y = RowMatrix::Zero(reach.num_rows, num_rows);  // P Jᵀ on the reach's rows
  for (int dof : touched) {
    const int row = reach.compact_row[l.permuted_index[dof]];
    for (Eigen::SparseMatrix<double>::InnerIterator it(J, dof); it; ++it)
      Y(row, it.row()) = it.value();
  }
  RowMatrix scratch(std::max(l.max_rows_below, 1), num_rows);
  SolveForward(l, L_values, reach, &Y, &scratch);
  SolveBackward(l, L_values, reach, &Y, &scratch);

  // W = J X with X = A⁻¹ Jᵀ, read at the touched dofs only: row r of W gains J(r, dof) X(dof, :),
  // added here as column r of Wᵀ (contiguous), which the symmetrisation below takes back.
  for (int dof : touched) {
    const auto X_dof = Y.row(reach.compact_row[l.permuted_index[dof]]).transpose();
    for (Eigen::SparseMatrix<double>::InnerIterator it(J, dof); it; ++it)
      W.col(it.row()) += it.value() * X_dof;
  }
  return 0.5 * (W + W.transpose());  // symmetric to rounding; exactly so for the solvers
}

}  // namespace hapsim::fem
