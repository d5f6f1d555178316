#include "fem/stiffness_assembly.h"

#include <algorithm>

namespace hapsim::fem {
namespace {

// Value index of entry (row, col) of a compressed column-major matrix, or -1.
int FindValueIndex(const Eigen::SparseMatrix<double>& A, int row, int col) {
  const int* rows = A.innerIndexPtr();
  const int* begin = rows + A.outerIndexPtr()[col];
  const int* end = rows + A.outerIndexPtr()[col + 1];
  const int* it = std::lower_bound(begin, end, row);
  return (it != end && *it == row) ? static_cast<int>(it - rows) : -1;
}

}  // namespace

StiffnessAssembler::StiffnessAssembler(const Model& model) {
  const int num_dofs = model.num_dofs();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(model.num_tets()) * 144);
  for (int t = 0; t < model.num_tets(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            entries.emplace_back(3 * model.mesh.tets(a, t) + r, 3 * model.mesh.tets(b, t) + c, 0.0);
  pattern_.resize(num_dofs, num_dofs);
  pattern_.setFromTriplets(entries.begin(), entries.end());
  pattern_.makeCompressed();

  block_value_index_.resize(model.num_tets());
  for (int t = 0; t < model.num_tets(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int c = 0; c < 3; ++c)
          block_value_index_[t][12 * a + 3 * b + c] =
              FindValueIndex(pattern_, 3 * model.mesh.tets(a, t), 3 * model.mesh.tets(b, t) + c);
  diagonal_value_index_.resize(num_dofs);
  for (int i = 0; i < num_dofs; ++i) diagonal_value_index_[i] = FindValueIndex(pattern_, i, i);
}

void StiffnessAssembler::Assemble(const Model& model, const std::vector<Eigen::Matrix3d>& rotations,
                                  Eigen::SparseMatrix<double>* K) const {
  double* values = K->valuePtr();
  std::fill(values, values + K->nonZeros(), 0.0);
  for (int t = 0; t < model.num_tets(); ++t) {
    const TetRestData& rest = model.tet_rest[t];
    const double mu_Pa = rest.lame_mu_Pa;
    const double lambda_Pa = rest.lame_lambda_Pa;
    const Eigen::Matrix<double, 3, 4>& b = rest.shape_gradients_1_m;
    const Eigen::Matrix<double, 3, 4> c = rotations[t] * b;
    const Eigen::Matrix4d gram = b.transpose() * b;  // b_a · b_b
    const std::array<int, 48>& index = block_value_index_[t];
    // K_ab = V (μ c_b c_aᵀ + λ c_a c_bᵀ + μ (b_a·b_b) I) and K_ba = K_abᵀ: each pair is computed
    // once (10 blocks, not 16) and scattered to both places.
    for (int a = 0; a < 4; ++a) {
      for (int bb = a; bb < 4; ++bb) {
        Eigen::Matrix3d block = (mu_Pa * rest.volume_m3) * (c.col(bb) * c.col(a).transpose()) +
                                (lambda_Pa * rest.volume_m3) * (c.col(a) * c.col(bb).transpose());
        block.diagonal().array() += mu_Pa * rest.volume_m3 * gram(a, bb);
        for (int col = 0; col < 3; ++col) {
          double* column = values + index[12 * a + 3 * bb + col];
          column[0] += block(0, col);
          column[1] += block(1, col);
          column[2] += block(2, col);
        }
        if (bb == a) continue;
        for (int col = 0; col < 3; ++col) {
          double* column = values + index[12 * bb + 3 * a + col];
          column[0] += block(col, 0);
          column[1] += block(col, 1);
          column[2] += block(col, 2);
        }
      }
    }
  }
}

}  // namespace hapsim::fem
