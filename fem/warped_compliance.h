#pragma once
// The body's contact compliance W_body = J_u A⁻¹ J_uᵀ (DESIGN.md §4) from a precomputed inverse
// of the system matrix at rest, warped by node rotations: the method of Saupin, Duriez & Cotin,
// "Contact model for haptic medical simulations" (ISBMS 2008), for corotational FEM.
//
// The corotational system matrix is A = M' + c Σ_e R_e K_e R_eᵀ, with A₀ its value at rest
// (R_e = I). Where the body's rotation varies slowly the element rotations are close to a node
// rotation R_n, and A⁻¹ ≈ R A₀⁻¹ Rᵀ with R = blockdiag(R_n), so
//
//   W_body(r, c) ≈ Σ_a Σ_b (R_aᵀ j_ra)ᵀ C₀_ab (R_bᵀ j_cb),   C₀_ab = E_aᵀ A₀⁻¹ E_b  (3 × 3)
//
// with j_ra the 3 entries of row r of J_u at node a and E_a the node's 3 columns of the
// identity. C₀ never changes, so each node's columns A₀⁻¹ E_a are solved once, the first time a
// contact touches the node, and kept at the rows of the nodes touched so far (C₀ is read only
// between contact nodes): one multi-column solve over all new nodes of the frame with a float
// copy of A₀'s factor (SinglePrecisionFactor::SolveColumnsAt), whose forward sweep works only on
// the new nodes' elimination-tree paths and whose backward sweep only on those of the nodes held;
// the columns are then exact to ~2e-7 relative. They fill a dense C₀ between the held nodes
// (9 H² doubles for H nodes, up to 4 times that with the capacity kept for new ones). A column of
// W then costs two dense passes over the rows' entries (an entry: a row group's weights at one
// node, rotated), q = C₀ Uᵀ e_c and W(:, c) = U q, instead of a forward solve with the current
// factor per row (fem/cholmod_factor.h CalcInverseQuadraticForm, the exact method). They read C₀
// by whole columns; a 3 × 3 product per pair of entries read it at scattered blocks and stalled on
// cache misses (a temporary stage timer, block_press in the linear mode, frames with ≥ 200
// contacts, 212 rows over 118 nodes: 0.73 → 0.57 ms; block_press_friction 2.24 against 2.37 ms,
// within the host's noise; docs/BENCHMARKS.md "fourth pass"). A frame may form W whole or only
// the columns its readers ask for (contact/frame_compliance.h).
//
// Node rotation: the polar rotation of the sum of the incident elements' rotations (their
// chordal mean). A node with a fixed dof keeps R = I (rotating would mix a fixed direction into
// a free one). Accuracy against the exact compliance is measured in
// tests/fem/contact_compliance_test.cc and on block_press in docs/CONTACT.md.

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <vector>

#include "fem/cholmod_factor.h"
#include "fem/compliance_column_kernels.h"
#include "fem/model.h"
#include "fem/time_stepper.h"

namespace hapsim::fem {

class WarpedCompliance {
 public:
  // Factors the stepper's rest system matrix A₀ (same Δt, damping and fixed dofs). `model` must
  // outlive this object. Throws std::runtime_error if A₀ is not positive definite.
  WarpedCompliance(const Model& model, const TimeStepper& stepper);

  // W_body ≈ J_u R C₀ Rᵀ J_uᵀ (rows × rows, symmetric) for the element rotations of the current
  // step (TimeStepper::rotations()): SetRows, then CalcAll.
  Eigen::MatrixXd Calc(const Eigen::SparseMatrix<double>& J_u,
                       const std::vector<Eigen::Matrix3d>& element_rotations);

  // J_u's rows rotated to the rest frame, R_aᵀ j_ra at each node a, in groups: consecutive rows
  // that touch the same nodes (a contact's normal and two tangent rows, at most 3) share one entry
  // per node, G = R_aᵀ [j_ra]_(r ∈ group) (column k: the group's row k), rotated once for them
  // all. They depend on the body and its rotations, not on A₀: the visual step's compliance and
  // the haptic step's share them (RotateRows once, SetRows on each).
  struct RotatedRows {
    struct Entry {
      int frame_node = 0;  // index into frame_nodes
      Eigen::Matrix3d G = Eigen::Matrix3d::Zero();
    };
    struct Group {
      Eigen::Index first_row = 0;
      int num_rows = 0;
      size_t first_entry = 0, num_entries = 0;  // in entries
    };
    Eigen::Index num_rows = 0;
    std::vector<int> frame_nodes;  // the nodes J_u touches, in order of first appearance
    std::vector<Group> groups;
    std::vector<Entry> entries;
  };
  // The rows of J_u at the element rotations of the current step (TimeStepper::rotations()).
  // Not const: it uses this object's scratch (frame_index_of_node_).
  RotatedRows RotateRows(const Eigen::SparseMatrix<double>& J_u,
                         const std::vector<Eigen::Matrix3d>& element_rotations);
  // The frame's rows, from this compliance's RotateRows or another's on the same model: solves
  // the columns of the nodes not seen before. The calls below read these rows until the next
  // SetRows. Throws std::invalid_argument for a node outside the model.
  void SetRows(const RotatedRows& rows);
  void SetRows(const Eigen::SparseMatrix<double>& J_u,
               const std::vector<Eigen::Matrix3d>& element_rotations) {
    SetRows(RotateRows(J_u, element_rotations));
  }
  // The whole W_body of the rows set.
  Eigen::MatrixXd CalcAll() const;
  // Only the given columns, W_body(:, c) for each c in `columns`, written into W (rows × rows;
  // its other columns are left as they are): what a solve needs that reads W by the columns of
  // its loaded rows (one pass over C₀ per column instead of per row). `whole` marks the columns
  // of W that are whole already (rows entries, 0 or 1): their rows of a new column are copied from
  // them, as W is symmetric, not computed; the columns formed here are marked. The columns so
  // formed differ from CalcAll's by round-off (each entry is summed once, from one side).
  void CalcColumns(const std::vector<Eigen::Index>& columns, Eigen::MatrixXd* W,
                   std::vector<std::uint8_t>* whole) const;
  // W_body(r, r) of every row, without a pass over C₀.
  Eigen::VectorXd CalcDiagonal() const;

  // Nodes whose columns of A₀⁻¹ are held (at the rows of the nodes held before them).
  int num_cached_nodes() const { return static_cast<int>(node_of_slot_.size()); }

 private:
  // Solves for the columns of those of `frame_nodes` (distinct) not held yet.
  void HoldColumnsOf(const std::vector<int>& frame_nodes);
  // The held C₀ between `nodes` (all held), in their order: 3 · nodes square.
  Eigen::MatrixXd GatherHeld(const std::vector<int>& nodes) const;
  // Makes room in held_compliance_ for num_nodes held nodes.
  void ReserveHeld(int num_nodes);
  Eigen::Matrix3d CalcNodeRotation(int node,
                                   const std::vector<Eigen::Matrix3d>& element_rotations) const;
  // C₀ between the frame's nodes, at the blocks the row entries name.
  Eigen::Ref<const Eigen::MatrixXd> FrameNodesCompliance() const;
  // q = C Uᵀ e_c, U the rows' rotated entries.
  void MultiplyRowByCompliance(const Eigen::Ref<const Eigen::MatrixXd>& C, Eigen::Index c,
                               Eigen::VectorXd* q) const;
  // (U q)_r, q a column of C Uᵀ.
  double MultiplyRow(Eigen::Index r, const double* q) const;

  const Model& model_;
  CholmodFactor factor_;
  std::vector<std::vector<int>> node_tets_;  // incident tets of each node
  std::vector<int> slot_of_node_;            // -1: not solved yet
  std::vector<int> node_of_slot_;
  // Scratch of RotateRows: -1 between calls; the index of each frame node during one.
  std::vector<int> frame_index_of_node_;
  // C₀ between the held nodes, slot by slot: block (s, t) = C₀_ab of the nodes of slots s and t,
  // taken from the column of the later of the two (SinglePrecisionFactor::SolveColumnsAt solves a
  // new node's column at the rows of the nodes held by then). Its size is a capacity: only the
  // first 3 · num_cached_nodes() rows and columns are set.
  Eigen::MatrixXd held_compliance_;

  // The rows set by SetRows: row r's entries are row_entries_[first_of_row_[r] ..
  // first_of_row_[r + 1]), each a node's rotated weights Rᵀ j_r and its block in the frame's C₀
  // (the held one in place, or frame_C_ gathered for the frame's nodes).
  using RowEntry = compliance_column::Entry;
  Eigen::Index num_rows_ = 0;
  std::vector<RowEntry> row_entries_;
  std::vector<size_t> first_of_row_;
  bool frame_C_is_gathered_ = false;
  Eigen::MatrixXd frame_C_;
};

}  // namespace hapsim::fem
