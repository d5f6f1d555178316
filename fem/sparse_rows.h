#pragma once
// A column-major sparse matrix read row by row: Aᵀ by a counting sort over A's columns, each
// row's entries in column order. For a contact Jacobian J_u (~200 rows, 3N columns) it replaced
// Eigen's transpose into a sparse matrix, which took 0.015 ms of block_press's frame: the warped
// compliance groups J_u's rows with it (fem/warped_compliance.cc) and SelectRows renumbers them
// (contact/contact_jacobian.cc).

#include <Eigen/SparseCore>
#include <numeric>
#include <utility>
#include <vector>

namespace hapsim::fem {

struct SparseRows {
  std::vector<int> start;                       // row r's entries: [start[r], start[r + 1])
  std::vector<std::pair<int, double>> entries;  // (column, value)
};

inline SparseRows GatherRows(const Eigen::SparseMatrix<double>& A) {
  SparseRows rows;
  rows.start.assign(static_cast<size_t>(A.rows()) + 1, 0);
  for (Eigen::Index j = 0; j < A.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it) ++rows.start[it.row() + 1];
  std::partial_sum(rows.start.begin(), rows.start.end(), rows.start.begin());
  rows.entries.resize(static_cast<size_t>(rows.start.back()));
  std::vector<int> next(rows.start.begin(), rows.start.end() - 1);
  for (Eigen::Index j = 0; j < A.outerSize(); ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(A, j); it; ++it)
      rows.entries[static_cast<size_t>(next[it.row()]++)] = {static_cast<int>(j), it.value()};
  return rows;
}

}  // namespace hapsim::fem
