#pragma once
// Warped stiffness K = Σ_e R_e K_e R_eᵀ (DESIGN.md §2), assembled into a sparse pattern built once.
//
// The 3×3 block of K_e coupling nodes a and b of a tet, from the shape gradients b_a, b_b, is
//   K_ab = V [ μ (b_a·b_b) I + μ b_b b_aᵀ + λ b_a b_bᵀ ],
// and rotating it only needs the rotated gradients c = R b:
//   R K_ab Rᵀ = V [ μ (b_a·b_b) I + μ c_b c_aᵀ + λ c_a c_bᵀ ].
// This is what makes assembly cheap: no 12×12 products per tet.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <vector>

#include "fem/model.h"

namespace hapsim::fem {

class StiffnessAssembler {
 public:
  // Builds the symmetric (full storage, column-major) pattern of all node pairs sharing a tet.
  explicit StiffnessAssembler(const Model& model);

  // Overwrites the values of *K (which must have this assembler's pattern; see MakeMatrix) with
  // Σ_e R_e K_e R_eᵀ. Allocates nothing.
  void Assemble(const Model& model, const std::vector<Eigen::Matrix3d>& rotations,
                Eigen::SparseMatrix<double>* K) const;

  // A matrix with the pattern and zero values.
  Eigen::SparseMatrix<double> MakeMatrix() const { return pattern_; }

  // Index into valuePtr() of the diagonal entry of each dof (3N).
  const std::vector<int>& diagonal_value_index() const { return diagonal_value_index_; }

 private:
  Eigen::SparseMatrix<double> pattern_;
  // Per tet, per block (a, b) and column c of it: the value index of row 3·node_a in column
  // 3·node_b + c; rows 3·node_a + r follow at + r because rows are sorted within a column.
  std::vector<std::array<int, 48>> block_value_index_;
  std::vector<int> diagonal_value_index_;
};

}  // namespace hapsim::fem
