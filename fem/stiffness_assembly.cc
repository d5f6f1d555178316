#include "fem/stiffness_assembly.h"

#include <algorithm>
#include <stdexcept>
#include <string>

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

StiffnessAssembler::StiffnessAssembler(const Model& model)
    : nodes_per_tet_(model.mesh.nodes_per_tet()),
      stride_(3 * nodes_per_tet_ * (nodes_per_tet_ + 1) / 2) {
  const int num_dofs = model.num_dofs();
  const int n = nodes_per_tet_;
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(static_cast<size_t>(model.num_tets()) * (3 * n) * (3 * n + 1) / 2);
  for (int t = 0; t < model.num_tets(); ++t)
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b)
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) {
            const int row = 3 * model.mesh.node(a, t) + r, col = 3 * model.mesh.node(b, t) + c;
            if (row >= col) entries.emplace_back(row, col, 0.0);
          }
  pattern_.resize(num_dofs, num_dofs);
  pattern_.setFromTriplets(entries.begin(), entries.end());
  pattern_.makeCompressed();

  // Pair (a, b ≥ a) of a tet is block (low, high) of the lower triangle, low the larger node:
  // columns 3·high + c hold rows 3·low + r. For a = b only the rows r ≥ c exist, from the diagonal.
  block_value_index_.resize(static_cast<size_t>(model.num_tets()) * stride_);
  for (int t = 0; t < model.num_tets(); ++t) {
    int* index = block_value_index_.data() + static_cast<size_t>(t) * stride_;
    int pair = 0;
    for (int a = 0; a < n; ++a)
      for (int b = a; b < n; ++b, ++pair) {
        const int na = model.mesh.node(a, t), nb = model.mesh.node(b, t);
        const int low = std::max(na, nb), high = std::min(na, nb);
        for (int c = 0; c < 3; ++c)
          index[3 * pair + c] = FindValueIndex(pattern_, 3 * low + (a == b ? c : 0), 3 * high + c);
      }
  }
  diagonal_value_index_.resize(num_dofs);
  for (int i = 0; i < num_dofs; ++i) {
    diagonal_value_index_[i] = FindValueIndex(pattern_, i, i);
    // The mass and the fixed-dof identity are written there (TimeStepper): a node in no tet has
    // no entry, and no stiffness or mass either.
    if (diagonal_value_index_[i] < 0)
      throw std::invalid_argument("StiffnessAssembler: node " + std::to_string(i / 3) +
                                  " belongs to no tet");
  }
}

namespace {

// Adds the 3 × 3 block of node pair (a, b) at `column` (3 value indices, as block_value_index_):
// its rows r ≥ c on the diagonal (a = b), else the block or its transpose, whichever lies in the
// lower triangle (node_a > node_b: the block itself, at rows of a and columns of b).
inline void AddBlock(const Eigen::Matrix3d& block, bool diagonal, bool a_is_lower,
                     const int* column, double* values) {
  if (diagonal) {
    values[column[0]] += block(0, 0), values[column[0] + 1] += block(1, 0);
    values[column[0] + 2] += block(2, 0);
    values[column[1]] += block(1, 1), values[column[1] + 1] += block(2, 1);
    values[column[2]] += block(2, 2);
  } else if (a_is_lower) {
    for (int col = 0; col < 3; ++col)
      for (int row = 0; row < 3; ++row) values[column[col] + row] += block(row, col);
  } else {
    for (int col = 0; col < 3; ++col)
      for (int row = 0; row < 3; ++row) values[column[col] + row] += block(col, row);
  }
}

}  // namespace

void StiffnessAssembler::Assemble(const Model& model, const std::vector<Eigen::Matrix3d>& rotations,
                                  double scale, Eigen::SparseMatrix<double>* K) const {
  double* values = K->valuePtr();
  std::fill(values, values + K->nonZeros(), 0.0);
  if (model.is_quadratic()) {
    AssembleQuadratic(model, rotations, scale, values);
    return;
  }
  for (int t = 0; t < model.num_tets(); ++t) {
    const TetRestData& rest = model.tet_rest[t];
    const double mu_V = scale * rest.lame_mu_Pa * rest.volume_m3;
    const double lambda_V = scale * rest.lame_lambda_Pa * rest.volume_m3;
    const Eigen::Matrix<double, 3, 4>& b = rest.shape_gradients_1_m;
    const Eigen::Matrix<double, 3, 4> c = rotations[t] * b;
    const Eigen::Matrix4d gram = b.transpose() * b;  // b_a · b_b
    const int* index = block_value_index_.data() + static_cast<size_t>(t) * stride_;
    // K_ab = V (μ c_b c_aᵀ + λ c_a c_bᵀ + μ (b_a·b_b) I): each pair is computed once (10 blocks,
    // not 16) and only its lower-triangle copy is stored.
    int pair = 0;
    for (int a = 0; a < 4; ++a) {
      for (int bb = a; bb < 4; ++bb, ++pair) {
        Eigen::Matrix3d block = mu_V * (c.col(bb) * c.col(a).transpose()) +
                                lambda_V * (c.col(a) * c.col(bb).transpose());
        block.diagonal().array() += mu_V * gram(a, bb);
        AddBlock(block, bb == a, model.mesh.tets(a, t) > model.mesh.tets(bb, t), index + 3 * pair,
                 values);
      }
    }
  }
}

// R K_e Rᵀ block by block, R K_ab Rᵀ for each of the 55 node pairs, from the stored K_e (packed
// in this pair order, so it is read once, front to back).
void StiffnessAssembler::AssembleQuadratic(const Model& model,
                                           const std::vector<Eigen::Matrix3d>& rotations,
                                           double scale, double* values) const {
  for (int t = 0; t < model.num_tets(); ++t) {
    const Eigen::Matrix3d R = rotations[t];
    const P2PackedStiffness& K_e = model.quadratic_stiffness[t];
    const int* index = block_value_index_.data() + static_cast<size_t>(t) * stride_;
    int pair = 0;
    for (int a = 0; a < kP2Nodes; ++a)
      for (int b = a; b < kP2Nodes; ++b, ++pair) {
        const Eigen::Matrix3d block = scale * (R * K_e.blocks[pair] * R.transpose());
        AddBlock(block, b == a, model.mesh.node(a, t) > model.mesh.node(b, t), index + 3 * pair,
                 values);
      }
  }
}

}  // namespace hapsim::fem
