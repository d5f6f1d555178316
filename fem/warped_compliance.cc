#include "fem/warped_compliance.h"

#include <algorithm>
#include <cstddef>
#include <stdexcept>
#include <utility>

#include "fem/polar_decomposition.h"
#include "fem/single_precision_factor.h"
#include "fem/sparse_rows.h"

namespace hapsim::fem {

WarpedCompliance::WarpedCompliance(const Model& model, const TimeStepper& stepper)
    : model_(model),
      node_tets_(model.num_nodes()),
      slot_of_node_(model.num_nodes(), -1),
      frame_index_of_node_(model.num_nodes(), -1) {
  factor_.KeepCopy(FactorPrecision::kSingle);
  if (!factor_.Factorize(stepper.MakeRestSystemMatrix()))
    throw std::runtime_error("WarpedCompliance: the rest system matrix is not positive definite");
  for (int e = 0; e < model.num_tets(); ++e)
    for (int k = 0; k < model.mesh.nodes_per_tet(); ++k)
      node_tets_[model.mesh.node(k, e)].push_back(e);
}

void WarpedCompliance::HoldColumnsOf(const std::vector<int>& frame_nodes) {
  std::vector<int> nodes;  // the new ones
  for (int node : frame_nodes)
    if (slot_of_node_[node] == -1) nodes.push_back(node);
  if (nodes.empty()) return;
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(model_.num_dofs(), 3 * nodes.size());
  for (size_t k = 0; k < nodes.size(); ++k)
    for (int d = 0; d < 3; ++d) E(3 * nodes[k] + d, 3 * k + d) = 1.0;
  // Only the rows of the nodes held so far and of the new ones, in slot order: C₀_ab is taken from
  // the column of whichever of a and b was solved later, at the rows of the other.
  std::vector<int> wanted_rows;
  wanted_rows.reserve(3 * (node_of_slot_.size() + nodes.size()));
  for (int node : node_of_slot_)
    for (int d = 0; d < 3; ++d) wanted_rows.push_back(3 * node + d);
  for (int node : nodes)
    for (int d = 0; d < 3; ++d) wanted_rows.push_back(3 * node + d);
  const Eigen::MatrixXd X = factor_.SolveColumnsWithCopyAt(E, wanted_rows);
  ReserveHeld(static_cast<int>(node_of_slot_.size() + nodes.size()));
  for (size_t k = 0; k < nodes.size(); ++k) {
    const int slot = static_cast<int>(node_of_slot_.size());
    slot_of_node_[nodes[k]] = slot;
    node_of_slot_.push_back(nodes[k]);
    // The column at the rows of slots 0 .. slot, and its transpose in the block row.
    const auto column = X.block(0, 3 * k, 3 * (slot + 1), 3);
    held_compliance_.block(0, 3 * slot, 3 * (slot + 1), 3) = column;
    held_compliance_.block(3 * slot, 0, 3, 3 * slot) = column.topRows(3 * slot).transpose();
    // C₀_aa comes from the float solve, symmetric only to ~1e-7; symmetric, C₀ makes W(r, c) and
    // W(c, r) equal to round-off however each is summed (CalcColumns).
    const Eigen::Matrix3d own = held_compliance_.block<3, 3>(3 * slot, 3 * slot);
    held_compliance_.block<3, 3>(3 * slot, 3 * slot) = 0.5 * (own + own.transpose());
  }
}

void WarpedCompliance::ReserveHeld(int num_nodes) {
  const int capacity = static_cast<int>(held_compliance_.rows() / 3);
  if (num_nodes <= capacity) return;
  // Doubling: a frame meeting new nodes copies the held blocks only when the capacity runs out.
  int grown = std::max(capacity, 64);
  while (grown < num_nodes) grown *= 2;
  grown = std::min(grown, model_.num_nodes());
  Eigen::MatrixXd bigger(3 * grown, 3 * grown);
  const int used = 3 * static_cast<int>(node_of_slot_.size());
  bigger.topLeftCorner(used, used) = held_compliance_.topLeftCorner(used, used);
  held_compliance_.swap(bigger);
}

Eigen::Matrix3d WarpedCompliance::CalcNodeRotation(
    int node, const std::vector<Eigen::Matrix3d>& element_rotations) const {
  for (int d = 0; d < 3; ++d)
    if (model_.dof_is_fixed[3 * node + d]) return Eigen::Matrix3d::Identity();
  Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
  for (int e : node_tets_[node]) sum += element_rotations[e];
  return CalcRotationOfDeformation(sum);
}

namespace {

using Group = WarpedCompliance::RotatedRows::Group;
using Entry = WarpedCompliance::RotatedRows::Entry;

// The groups of J_u's rows and their entries, frame_node holding the node itself and G as J_u
// holds it (not yet rotated).
void GroupRows(const Eigen::SparseMatrix<double>& J_u, std::vector<Group>* groups,
               std::vector<Entry>* entries) {
  const SparseRows by_row = GatherRows(J_u);  // each row's entries in dof order, node by node
  std::vector<Entry> row_entries;
  for (Eigen::Index r = 0; r < J_u.rows(); ++r) {
    row_entries.clear();
    for (int k = by_row.start[r]; k < by_row.start[r + 1]; ++k) {
      const auto [dof, value] = by_row.entries[k];
      const int node = dof / 3;
      if (row_entries.empty() || row_entries.back().frame_node != node)
        row_entries.push_back({node});
      row_entries.back().G(dof % 3, 0) = value;
    }
    const bool joins =
        !groups->empty() && groups->back().num_rows < 3 &&
        groups->back().num_entries == row_entries.size() &&
        std::equal(row_entries.begin(), row_entries.end(),
                   entries->begin() + static_cast<std::ptrdiff_t>(groups->back().first_entry),
                   [](const Entry& a, const Entry& b) { return a.frame_node == b.frame_node; });
    if (!joins) {
      groups->push_back({r, 0, entries->size(), row_entries.size()});
      for (const Entry& e : row_entries) entries->push_back({e.frame_node});
    }
    Group& group = groups->back();
    for (size_t k = 0; k < row_entries.size(); ++k)
      (*entries)[group.first_entry + k].G.col(group.num_rows) = row_entries[k].G.col(0);
    ++group.num_rows;
  }
}

}  // namespace

WarpedCompliance::RotatedRows WarpedCompliance::RotateRows(
    const Eigen::SparseMatrix<double>& J_u, const std::vector<Eigen::Matrix3d>& element_rotations) {
  if (J_u.cols() != model_.num_dofs())
    throw std::invalid_argument("WarpedCompliance::RotateRows: J_u needs a column per dof");
  RotatedRows rows;
  rows.num_rows = J_u.rows();
  GroupRows(J_u, &rows.groups, &rows.entries);
  // The frame's nodes in order of first appearance; each entry then names its node's index.
  for (Entry& entry : rows.entries) {
    int& index = frame_index_of_node_[entry.frame_node];
    if (index == -1) {
      index = static_cast<int>(rows.frame_nodes.size());
      rows.frame_nodes.push_back(entry.frame_node);
    }
    entry.frame_node = index;
  }
  for (int node : rows.frame_nodes) frame_index_of_node_[node] = -1;
  std::vector<Eigen::Matrix3d> rotations_T(rows.frame_nodes.size());
  for (size_t k = 0; k < rows.frame_nodes.size(); ++k)
    rotations_T[k] = CalcNodeRotation(rows.frame_nodes[k], element_rotations).transpose();
  for (Entry& entry : rows.entries) entry.G = rotations_T[entry.frame_node] * entry.G;
  return rows;
}

void WarpedCompliance::SetRows(const RotatedRows& rows) {
  for (int node : rows.frame_nodes)
    if (node < 0 || node >= model_.num_nodes())
      throw std::invalid_argument("WarpedCompliance::SetRows: a node outside the model");
  HoldColumnsOf(rows.frame_nodes);
  // A pass over C₀ costs 3 · (C's nodes) a column per entry: C₀ is read in place while the held
  // nodes are not many more than the frame's, and gathered for the frame's nodes once they are
  // (a long session that has touched much of the surface).
  const Eigen::Index held_dofs = 3 * static_cast<Eigen::Index>(node_of_slot_.size());
  frame_C_is_gathered_ = held_dofs > 2 * 3 * static_cast<Eigen::Index>(rows.frame_nodes.size());
  if (frame_C_is_gathered_) frame_C_ = GatherHeld(rows.frame_nodes);
  const auto block_of = [&](const Entry& entry) {
    return frame_C_is_gathered_ ? 3 * entry.frame_node
                                : 3 * slot_of_node_[rows.frame_nodes[entry.frame_node]];
  };
  // Each row's entries side by side (a group's entries once for each of its rows, with that
  // row's weights), so that a row's product with a column of C₀ is one short sum.
  num_rows_ = rows.num_rows;
  row_entries_.clear();
  first_of_row_.assign(static_cast<size_t>(num_rows_) + 1, 0);
  for (const Group& group : rows.groups)
    for (int k = 0; k < group.num_rows; ++k) {
      first_of_row_[group.first_row + k] = row_entries_.size();
      for (size_t i = 0; i < group.num_entries; ++i) {
        const Entry& a = rows.entries[group.first_entry + i];
        row_entries_.push_back({block_of(a), a.G(0, k), a.G(1, k), a.G(2, k)});
      }
    }
  first_of_row_[num_rows_] = row_entries_.size();
}

Eigen::Ref<const Eigen::MatrixXd> WarpedCompliance::FrameNodesCompliance() const {
  if (frame_C_is_gathered_) return frame_C_;
  const Eigen::Index held_dofs = 3 * static_cast<Eigen::Index>(node_of_slot_.size());
  return held_compliance_.topLeftCorner(held_dofs, held_dofs);
}

// q = C Uᵀ e_c: row c's entries, each adding 3 of C's columns times its weights. The columns are
// summed as columns (fem/compliance_column_kernels.h), not as an Eigen block product of run-time
// width, whose general product dispatch cost more than the arithmetic on block_press's ~210 rows.
void WarpedCompliance::MultiplyRowByCompliance(const Eigen::Ref<const Eigen::MatrixXd>& C,
                                               Eigen::Index c, Eigen::VectorXd* q) const {
  q->resize(C.rows());
  const RowEntry* entries = row_entries_.data() + first_of_row_[c];
  const int count = static_cast<int>(first_of_row_[c + 1] - first_of_row_[c]);
#if defined(__x86_64__)  // the AVX2 kernel is built there only
  if (SinglePrecisionFactor::CpuHasVectorKernels()) {
    compliance_column::AccumulateAvx2(C.data(), C.outerStride(), C.rows(), entries, count,
                                      q->data());
    return;
  }
#endif
  compliance_column::Accumulate(C.data(), C.outerStride(), C.rows(), entries, count, q->data());
}

// (U q)_r: row r gathers its entries' 3 values of q. The one sum of a row with a column, for
// CalcAll, CalcColumns and (in the same order) CalcDiagonal.
double WarpedCompliance::MultiplyRow(Eigen::Index r, const double* q) const {
  double sum = 0.0;
  for (size_t e = first_of_row_[r]; e < first_of_row_[r + 1]; ++e) {
    const RowEntry& a = row_entries_[e];
    sum += a.g0 * q[a.block] + a.g1 * q[a.block + 1] + a.g2 * q[a.block + 2];
  }
  return sum;
}

// W = U C Uᵀ column by column, q = C Uᵀ e_c then W(c.., c) = U q: q stays in cache while the rows
// read it. Only the lower triangle is computed; W mirrors it.
Eigen::MatrixXd WarpedCompliance::CalcAll() const {
  const Eigen::Ref<const Eigen::MatrixXd> C = FrameNodesCompliance();
  Eigen::MatrixXd W(num_rows_, num_rows_);
  Eigen::VectorXd q;
  for (Eigen::Index c = 0; c < num_rows_; ++c) {
    MultiplyRowByCompliance(C, c, &q);
    for (Eigen::Index r = c; r < num_rows_; ++r) W(r, c) = MultiplyRow(r, q.data());
  }
  W.triangularView<Eigen::StrictlyUpper>() = W.transpose();
  return W;
}

void WarpedCompliance::CalcColumns(const std::vector<Eigen::Index>& columns, Eigen::MatrixXd* W,
                                   std::vector<std::uint8_t>* whole) const {
  if (W->rows() != num_rows_ || W->cols() != num_rows_ ||
      whole->size() != static_cast<size_t>(num_rows_))
    throw std::invalid_argument("WarpedCompliance::CalcColumns: W must be rows x rows");
  const Eigen::Ref<const Eigen::MatrixXd> C = FrameNodesCompliance();
  Eigen::VectorXd q;
  for (Eigen::Index c : columns) {
    MultiplyRowByCompliance(C, c, &q);
    // Row by row: W(r, c) = W(c, r) where column r is whole already (C₀ is symmetric), else U_r q.
    for (Eigen::Index r = 0; r < num_rows_; ++r)
      (*W)(r, c) = (*whole)[r] ? (*W)(c, r) : MultiplyRow(r, q.data());
    (*whole)[c] = 1;
  }
}

// W(r, r) = U_r q_r with only the entries of q_r = C Uᵀ e_r that row r reads, each summed in the
// order MultiplyRowByCompliance and MultiplyRow sum it: the diagonal is the formed columns'
// own, bit for bit (a row's own entry exported alone must not depend on whether its column was
// formed).
Eigen::VectorXd WarpedCompliance::CalcDiagonal() const {
  const Eigen::Ref<const Eigen::MatrixXd> C = FrameNodesCompliance();
  Eigen::VectorXd diagonal(num_rows_);
  for (Eigen::Index r = 0; r < num_rows_; ++r) {
    double sum = 0.0;
    for (size_t e = first_of_row_[r]; e < first_of_row_[r + 1]; ++e) {
      const RowEntry& a = row_entries_[e];
      double q[3] = {0.0, 0.0, 0.0};
      for (size_t f = first_of_row_[r]; f < first_of_row_[r + 1]; ++f) {
        const RowEntry& b = row_entries_[f];
        for (int k = 0; k < 3; ++k)
          q[k] += b.g0 * C(a.block + k, b.block) + b.g1 * C(a.block + k, b.block + 1) +
                  b.g2 * C(a.block + k, b.block + 2);
      }
      sum += a.g0 * q[0] + a.g1 * q[1] + a.g2 * q[2];
    }
    diagonal[r] = sum;
  }
  return diagonal;
}

Eigen::MatrixXd WarpedCompliance::Calc(const Eigen::SparseMatrix<double>& J_u,
                                       const std::vector<Eigen::Matrix3d>& element_rotations) {
  SetRows(J_u, element_rotations);
  return CalcAll();
}

Eigen::MatrixXd WarpedCompliance::GatherHeld(const std::vector<int>& nodes) const {
  const Eigen::Index n = static_cast<Eigen::Index>(nodes.size());
  std::vector<Eigen::Index> held_row(nodes.size());
  for (size_t a = 0; a < nodes.size(); ++a) held_row[a] = 3 * slot_of_node_[nodes[a]];
  // Column by column: each of C's columns gathers 3 consecutive entries per node from one held
  // column, which the loads walk through in order when the frame's nodes are held in order.
  Eigen::MatrixXd C(3 * n, 3 * n);
  for (Eigen::Index b = 0; b < n; ++b)
    for (int d = 0; d < 3; ++d) {
      const double* from = held_compliance_.col(held_row[b] + d).data();
      double* to = C.col(3 * b + d).data();
      for (Eigen::Index a = 0; a < n; ++a) std::copy_n(from + held_row[a], 3, to + 3 * a);
    }
  return C;
}

}  // namespace hapsim::fem
