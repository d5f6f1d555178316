#pragma once
// Warped stiffness K = Σ_e R_e K_e R_eᵀ (DESIGN.md §2), assembled into a sparse pattern built once.
// Linear tets as below; quadratic ones (fem/quadratic_tet.h) from their stored K_e, R K_ab Rᵀ for
// each of the 55 node pairs of a tet.
//
// The 3×3 block of K_e coupling nodes a and b of a tet, from the shape gradients b_a, b_b, is
//   K_ab = V [ μ (b_a·b_b) I + μ b_b b_aᵀ + λ b_a b_bᵀ ],
// and rotating it only needs the rotated gradients c = R b:
//   R K_ab Rᵀ = V [ μ (b_a·b_b) I + μ c_b c_aᵀ + λ c_a c_bᵀ ].
// This is what makes assembly cheap: no 12×12 products per tet.
//
// Only the lower triangle (row ≥ column) is stored: K is symmetric, CHOLMOD reads only that half,
// and CG's products with A = M + … K (fem/cg_solver.h MultiplySymmetric) use each stored entry
// twice. Against
// full storage this halves the scattered writes of assembly and the matrix a product streams:
// assembly 4.5 → 3.8 ms at 28.8k tets and 0.49 → 0.43 ms at 3.6k, the 3.6k step's mean 1.35 →
// 1.24 ms (fem --bench, both builds alternating, 2026-11-26). Read it as a full matrix with
// K.selfadjointView<Eigen::Lower>().

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <array>
#include <vector>

#include "fem/model.h"

namespace hapsim::fem {

class StiffnessAssembler {
 public:
  // Builds the lower triangle (column-major) of the pattern of all node pairs sharing a tet (its 4
  // corners, or all 10 nodes of a quadratic tet).
  explicit StiffnessAssembler(const Model& model);

  // Overwrites the values of *K (which must have this assembler's pattern; see MakeMatrix) with
  // scale · Σ_e R_e K_e R_eᵀ. The implicit step wants (Δt β + Δt²) K: scaling the element
  // constants saves a pass over the matrix. Allocates nothing.
  void Assemble(const Model& model, const std::vector<Eigen::Matrix3d>& rotations, double scale,
                Eigen::SparseMatrix<double>* K) const;

  // A matrix with the pattern and zero values.
  Eigen::SparseMatrix<double> MakeMatrix() const { return pattern_; }

  // Index into valuePtr() of the diagonal entry of each dof (3N).
  const std::vector<int>& diagonal_value_index() const { return diagonal_value_index_; }

 private:
  void AssembleQuadratic(const Model& model, const std::vector<Eigen::Matrix3d>& rotations,
                         double scale, double* values) const;

  int nodes_per_tet_;
  int stride_;  // entries of block_value_index_ per tet: 3 per node pair (30 linear, 165 quadratic)
  Eigen::SparseMatrix<double> pattern_;
  // Per tet (stride_ entries), per node pair p = (a, b ≥ a) in the order (0,0) (0,1) .. (n−1,n−1),
  // and column c of its block in the lower triangle (columns of the smaller node, rows of the
  // larger): the value index of the block's first row in that column; the other rows follow at
  // + 1, + 2 because rows are sorted within a column. A diagonal block (a = b) holds rows r ≥ c,
  // from the diagonal entry.
  std::vector<int> block_value_index_;
  std::vector<int> diagonal_value_index_;
};

}  // namespace hapsim::fem
