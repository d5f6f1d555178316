#include "fem/single_precision_factor.h"

#include <Eigen/Dense>
#include <algorithm>
#include <stdexcept>
#include <string>

#include "fem/float_column_sweeps.h"

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

// The kernels of fem/float_column_sweeps.h in plain loops, in the order the AVX2 ones use.
struct PortableKernels {
  static void SubtractProduct(const float* L, long lda, int rows, int cols, const float* X,
                              float* out, int width) {
    for (int i = 0; i < rows; ++i)
      for (int c = 0; c < cols; ++c)
        for (int j = 0; j < width; ++j)
          out[static_cast<long>(i) * width + j] =
              out[static_cast<long>(i) * width + j] -
              L[c * lda + i] * X[static_cast<long>(c) * width + j];
  }

  static void SubtractTransposedProduct(const float* L, long lda, int rows, int cols,
                                        const float* known, float* Z, int width) {
    for (int c = 0; c < cols; ++c)
      for (int i = 0; i < rows; ++i)
        for (int j = 0; j < width; ++j)
          Z[static_cast<long>(c) * width + j] =
              Z[static_cast<long>(c) * width + j] -
              L[c * lda + i] * known[static_cast<long>(i) * width + j];
  }
};

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

bool SinglePrecisionFactor::CpuHasVectorKernels() {
#if defined(__x86_64__)
  static const bool has = __builtin_cpu_supports("avx2");
  return has;
#else
  return false;
#endif
}

Eigen::MatrixXd SinglePrecisionFactor::SolveColumns(const Eigen::MatrixXd& B,
                                                    Kernels kernels) const {
  int width = 0;
  const std::vector<float> Y = SolvePermutedColumns(B, nullptr, kernels, &width);
  Eigen::MatrixXd X(B.rows(), B.cols());
  for (int k = 0; k < layout_.size(); ++k)  // X = Pᵀ Y
    for (Eigen::Index j = 0; j < B.cols(); ++j)
      X(layout_.perm[k], j) = Y[static_cast<size_t>(k) * width + j];
  return X;
}

Eigen::MatrixXd SinglePrecisionFactor::SolveColumnsAt(const Eigen::MatrixXd& B,
                                                      const std::vector<int>& wanted_rows,
                                                      Kernels kernels) const {
  const SupernodalLayout& l = layout_;
  if (B.rows() != l.size())
    throw std::invalid_argument("SolveColumnsAt: B has " + std::to_string(B.rows()) +
                                " rows, the factor " + std::to_string(l.size()));
  for (int row : wanted_rows)
    if (row < 0 || row >= l.size())
      throw std::invalid_argument("SolveColumnsAt: wanted row " + std::to_string(row) +
                                  " is outside 0.." + std::to_string(l.size() - 1));
  std::vector<char> needed(l.num_supernodes(), 0);
  for (int row : wanted_rows)
    for (int sn = l.supernode_of_column[l.permuted_index[row]]; sn != -1 && !needed[sn];
         sn = l.parent[sn])
      needed[sn] = 1;
  int width = 0;
  const std::vector<float> Y = SolvePermutedColumns(B, &needed, kernels, &width);
  Eigen::MatrixXd X(wanted_rows.size(), B.cols());
  for (size_t i = 0; i < wanted_rows.size(); ++i)
    for (Eigen::Index j = 0; j < B.cols(); ++j)
      X(i, j) = Y[static_cast<size_t>(l.permuted_index[wanted_rows[i]]) * width + j];
  return X;
}

std::vector<float> SinglePrecisionFactor::SolvePermutedColumns(const Eigen::MatrixXd& B,
                                                               const std::vector<char>* needed,
                                                               Kernels kernels, int* width) const {
  const SupernodalLayout& l = layout_;
  const int n = l.size();
  *width = static_cast<int>((B.cols() + 7) / 8 * 8);
  std::vector<float> Y(static_cast<size_t>(n) * *width, 0.0f);  // Y = P B, rows padded with zeros
  for (int k = 0; k < n; ++k)
    for (Eigen::Index j = 0; j < B.cols(); ++j)
      Y[static_cast<size_t>(k) * *width + j] = static_cast<float>(B(l.perm[k], j));
  std::vector<float> scratch(static_cast<size_t>(std::max(l.max_rows_below, 1)) * *width);
  const float_columns::SweepArgs args{l.num_supernodes(), l.super.data(),
                                      l.pi.data(),        l.px.data(),
                                      l.s.data(),         values_.data(),
                                      Y.data(),           *width,
                                      scratch.data(),     needed ? needed->data() : nullptr};
#if defined(__x86_64__)
  if (kernels == Kernels::kFastest && CpuHasVectorKernels()) {
    float_columns::SolveColumnsWithAvx2(args);
    return Y;
  }
#endif
  float_columns::SolveColumns<PortableKernels>(args);
  return Y;
}

}  // namespace hapsim::fem
