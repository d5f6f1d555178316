#include "fem/single_precision_factor.h"

#include <Eigen/Dense>
#include <stdexcept>

namespace hapsim::fem {
namespace {

using BlockMap = Eigen::Map<const Eigen::MatrixXf, 0, Eigen::OuterStride<>>;

// Supernodes of at most this many columns take plain loops instead of Eigen's dense kernels:
// most supernodes are one mesh node (3 columns; 413 of 489 on the 3.6k-tet block, 2478 of 3000 on
// the 28.8k one), and for them the setup of Eigen's triangular solve and product cost more than
// the arithmetic.
constexpr int kSmallSupernodeColumns = 4;

// Forward step of one small supernode: y_cols ← D⁻¹ y_cols (D the lower-triangular diagonal
// block), then y[rows] −= B y_cols (B the rows below), reading L column by column as stored.
void SolveSmallForward(const float* L, int nsrow, int nscol, const int* rows_below, float* y_cols,
                       float* y) {
  for (int c = 0; c < nscol; ++c) {
    const float* column = L + c * nsrow;
    const float y_c = y_cols[c] / column[c];
    y_cols[c] = y_c;
    for (int r = c + 1; r < nscol; ++r) y_cols[r] -= column[r] * y_c;
    for (int i = 0, below = nsrow - nscol; i < below; ++i)
      y[rows_below[i]] -= column[nscol + i] * y_c;
  }
}

// Backward step: y_cols ← D⁻ᵀ (y_cols − Bᵀ y[rows]).
void SolveSmallBackward(const float* L, int nsrow, int nscol, const int* rows_below, float* y_cols,
                        const float* y) {
  for (int c = nscol - 1; c >= 0; --c) {
    const float* column = L + c * nsrow;
    float sum = y_cols[c];
    for (int i = 0, below = nsrow - nscol; i < below; ++i)
      sum -= column[nscol + i] * y[rows_below[i]];
    for (int r = c + 1; r < nscol; ++r) sum -= column[r] * y_cols[r];
    y_cols[c] = sum / column[c];
  }
}

}  // namespace

void SinglePrecisionFactor::Assign(const cholmod_factor& L) {
  layout_.Assign(L);
  const double* x = static_cast<const double*>(L.x);
  values_.assign(x, x + L.xsize);  // rounds each entry to the nearest float
  y_.resize(static_cast<Eigen::Index>(L.n));
  gathered_.resize(layout_.max_rows_below);
}

void SinglePrecisionFactor::Solve(const Eigen::VectorXd& b, Eigen::VectorXd* x) const {
  const SupernodalLayout& l = layout_;
  const int n = l.size();
  for (int k = 0; k < n; ++k) y_[k] = static_cast<float>(b[l.perm[k]]);  // y = P b
  // Forward, y ← L⁻¹ y, supernode by supernode: the diagonal block, then the rows below it.
  for (int sn = 0; sn < l.num_supernodes(); ++sn) {
    const int k1 = l.first_column(sn), nscol = l.num_columns(sn);
    const int nsrow = l.num_rows(sn), below = nsrow - nscol;
    if (nscol <= kSmallSupernodeColumns) {
      SolveSmallForward(values_.data() + l.px[sn], nsrow, nscol, l.rows_below(sn), y_.data() + k1,
                        y_.data());
      continue;
    }
    const BlockMap block(values_.data() + l.px[sn], nsrow, nscol, Eigen::OuterStride<>(nsrow));
    auto y_cols = y_.segment(k1, nscol);
    block.topRows(nscol).triangularView<Eigen::Lower>().solveInPlace(y_cols);
    if (below == 0) continue;
    auto update = gathered_.head(below);
    update.noalias() = block.bottomRows(below) * y_cols;
    const int* rows = l.rows_below(sn);
    for (int i = 0; i < below; ++i) y_[rows[i]] -= update[i];
  }
  // Backward, y ← L⁻ᵀ y, in reverse: the rows below first, then the diagonal block.
  for (int sn = l.num_supernodes() - 1; sn >= 0; --sn) {
    const int k1 = l.first_column(sn), nscol = l.num_columns(sn);
    const int nsrow = l.num_rows(sn), below = nsrow - nscol;
    if (nscol <= kSmallSupernodeColumns) {
      SolveSmallBackward(values_.data() + l.px[sn], nsrow, nscol, l.rows_below(sn), y_.data() + k1,
                         y_.data());
      continue;
    }
    const BlockMap block(values_.data() + l.px[sn], nsrow, nscol, Eigen::OuterStride<>(nsrow));
    auto y_cols = y_.segment(k1, nscol);
    if (below > 0) {
      auto known = gathered_.head(below);
      const int* rows = l.rows_below(sn);
      for (int i = 0; i < below; ++i) known[i] = y_[rows[i]];
      y_cols.noalias() -= block.bottomRows(below).transpose() * known;
    }
    block.topRows(nscol).triangularView<Eigen::Lower>().transpose().solveInPlace(y_cols);
  }
  x->resize(n);
  for (int k = 0; k < n; ++k) (*x)[l.perm[k]] = y_[k];  // x = Pᵀ y
}

Eigen::MatrixXd SinglePrecisionFactor::SolveColumns(const Eigen::MatrixXd& B) const {
  const RowMajorXf Y = SolvePermutedColumns(B, nullptr);
  Eigen::MatrixXd X(Y.rows(), Y.cols());
  for (Eigen::Index k = 0; k < Y.rows(); ++k) X.row(layout_.perm[k]) = Y.row(k).cast<double>();
  return X;  // X = Pᵀ Y
}

Eigen::MatrixXd SinglePrecisionFactor::SolveColumnsAt(const Eigen::MatrixXd& B,
                                                      const std::vector<int>& wanted_rows) const {
  const SupernodalLayout& l = layout_;
  std::vector<char> needed(l.num_supernodes(), 0);
  for (int row : wanted_rows)
    for (int sn = l.supernode_of_column[l.permuted_index[row]]; sn != -1 && !needed[sn];
         sn = l.parent[sn])
      needed[sn] = 1;
  const RowMajorXf Y = SolvePermutedColumns(B, &needed);
  Eigen::MatrixXd X(wanted_rows.size(), Y.cols());
  for (size_t i = 0; i < wanted_rows.size(); ++i)
    X.row(i) = Y.row(l.permuted_index[wanted_rows[i]]).cast<double>();
  return X;
}

SinglePrecisionFactor::RowMajorXf SinglePrecisionFactor::SolvePermutedColumns(
    const Eigen::MatrixXd& B, const std::vector<char>* needed) const {
  const SupernodalLayout& l = layout_;
  const int n = l.size();
  const Eigen::Index k = B.cols();
  // Row-major: a row of L's update is one contiguous row of Y, gathered and scattered whole.
  RowMajorXf Y(n, k), rows_below(l.max_rows_below, k);
  for (int i = 0; i < n; ++i) Y.row(i) = B.row(l.perm[i]).cast<float>();  // Y = P B
  for (int sn = 0; sn < l.num_supernodes(); ++sn) {
    const int k1 = l.first_column(sn), nscol = l.num_columns(sn);
    const int nsrow = l.num_rows(sn), below = nsrow - nscol;
    auto Y_cols = Y.middleRows(k1, nscol);
    if (Y_cols.isZero(0.0)) continue;  // L⁻¹ keeps zero what no earlier column reached
    const BlockMap block(values_.data() + l.px[sn], nsrow, nscol, Eigen::OuterStride<>(nsrow));
    block.topRows(nscol).triangularView<Eigen::Lower>().solveInPlace(Y_cols);
    if (below == 0) continue;
    auto update = rows_below.topRows(below);
    update.noalias() = block.bottomRows(below) * Y_cols;
    const int* rows = l.rows_below(sn);
    for (int i = 0; i < below; ++i) Y.row(rows[i]) -= update.row(i);
  }
  // A backward step reads only the rows below the supernode's diagonal block, which lie in its
  // ancestors: a needed supernode's ancestors are needed too, so skipping the others changes no
  // needed entry.
  for (int sn = l.num_supernodes() - 1; sn >= 0; --sn) {
    const int k1 = l.first_column(sn), nscol = l.num_columns(sn);
    if (needed && !(*needed)[sn]) continue;
    auto Y_cols = Y.middleRows(k1, nscol);
    const int nsrow = l.num_rows(sn), below = nsrow - nscol;
    const BlockMap block(values_.data() + l.px[sn], nsrow, nscol, Eigen::OuterStride<>(nsrow));
    if (below > 0) {
      auto known = rows_below.topRows(below);
      const int* rows = l.rows_below(sn);
      for (int i = 0; i < below; ++i) known.row(i) = Y.row(rows[i]);
      Y_cols.noalias() -= block.bottomRows(below).transpose() * known;
    }
    block.topRows(nscol).triangularView<Eigen::Lower>().transpose().solveInPlace(Y_cols);
  }
  return Y;
}

}  // namespace hapsim::fem
