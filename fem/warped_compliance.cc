#include "fem/warped_compliance.h"

#include <algorithm>
#include <cstddef>
#include <stdexcept>

#include "fem/polar_decomposition.h"

namespace hapsim::fem {

WarpedCompliance::WarpedCompliance(const Model& model, const TimeStepper& stepper)
    : model_(model), node_tets_(model.num_nodes()), slot_of_node_(model.num_nodes(), -1) {
  factor_.KeepCopy(FactorPrecision::kSingle);
  if (!factor_.Factorize(stepper.MakeRestSystemMatrix()))
    throw std::runtime_error("WarpedCompliance: the rest system matrix is not positive definite");
  for (int e = 0; e < model.num_tets(); ++e)
    for (int k = 0; k < 4; ++k) node_tets_[model.mesh.tets(k, e)].push_back(e);
}

void WarpedCompliance::SolveForNewNodes(const std::vector<int>& nodes) {
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

// Rows of J_u in groups: consecutive rows that touch the same nodes with their entries (a
// contact's normal and two tangent rows, at most 3 rows a group). A group's rows share node
// rotations and C₀ blocks, so W's block between groups g and h is one small product per pair of
// their nodes,
//
//   W_gh = Σ_a Σ_b G_gaᵀ C₀_ab G_hb,   G_ga = R_aᵀ [j_ra]_(r ∈ g)  (3 × rows of g),
//
// which for friction rows is 9× fewer pairs than row by row (block_press_friction's 720 rows:
// 2.4 → 1.3–1.9 ms a frame, means over `hapsim sim` runs, 2026-11-27).
struct GroupEntry {
  int node;
  Eigen::Matrix3d G = Eigen::Matrix3d::Zero();  // column k: the group's row k at the node
  int block = 0;  // 3 · the node's slot: its rows and columns in held_compliance_
};
struct RowGroup {
  Eigen::Index first_row = 0;
  int num_rows = 0;
  size_t first_entry = 0, num_entries = 0;  // in the GroupEntry list
};

// The groups of J_u's rows and their entries (G as J_u holds it: not yet rotated).
void GroupRows(const Eigen::SparseMatrix<double>& J_u, std::vector<RowGroup>* groups,
               std::vector<GroupEntry>* entries) {
  // J_uᵀ is column-major with sorted rows, so its column r lists row r's entries node by node.
  const Eigen::SparseMatrix<double> Jt = J_u.transpose();
  std::vector<GroupEntry> row_entries;
  for (Eigen::Index r = 0; r < J_u.rows(); ++r) {
    row_entries.clear();
    for (Eigen::SparseMatrix<double>::InnerIterator it(Jt, r); it; ++it) {
      const int node = static_cast<int>(it.row() / 3);
      if (row_entries.empty() || row_entries.back().node != node) row_entries.push_back({node});
      row_entries.back().G(it.row() % 3, 0) = it.value();
    }
    const bool joins =
        !groups->empty() && groups->back().num_rows < 3 &&
        groups->back().num_entries == row_entries.size() &&
        std::equal(row_entries.begin(), row_entries.end(),
                   entries->begin() + static_cast<std::ptrdiff_t>(groups->back().first_entry),
                   [](const GroupEntry& a, const GroupEntry& b) { return a.node == b.node; });
    if (!joins) {
      groups->push_back({r, 0, entries->size(), row_entries.size()});
      for (const GroupEntry& e : row_entries) entries->push_back({e.node});
    }
    RowGroup& group = groups->back();
    for (size_t k = 0; k < row_entries.size(); ++k)
      (*entries)[group.first_entry + k].G.col(group.num_rows) = row_entries[k].G.col(0);
    ++group.num_rows;
  }
}

// W_gh above (its top-left num_rows(g) × num_rows(h) corner), from the rotated entries.
Eigen::Matrix3d CalcGroupBlock(const RowGroup& g, const RowGroup& h,
                               const std::vector<GroupEntry>& entries,
                               const Eigen::MatrixXd& held_compliance) {
  Eigen::Matrix3d W_gh = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < g.num_entries; ++i)
    for (size_t k = 0; k < h.num_entries; ++k) {
      const GroupEntry& a = entries[g.first_entry + i];
      const GroupEntry& b = entries[h.first_entry + k];
      const auto C_ab = held_compliance.block<3, 3>(a.block, b.block);
      if (g.num_rows == 1 && h.num_rows == 1)  // normal rows alone: one number
        W_gh(0, 0) += a.G.col(0).dot(C_ab * b.G.col(0));
      else
        W_gh.noalias() += a.G.transpose() * (C_ab * b.G);
    }
  if (&g == &h) W_gh = 0.5 * (W_gh + W_gh.transpose()).eval();  // C₀_aa is a float solve's
  return W_gh;
}

}  // namespace

Eigen::MatrixXd WarpedCompliance::Calc(const Eigen::SparseMatrix<double>& J_u,
                                       const std::vector<Eigen::Matrix3d>& element_rotations) {
  std::vector<RowGroup> groups;
  std::vector<GroupEntry> entries;
  GroupRows(J_u, &groups, &entries);
  std::vector<int> new_nodes;
  for (const GroupEntry& entry : entries)
    if (slot_of_node_[entry.node] == -1) {
      slot_of_node_[entry.node] = -2;  // queued for this frame's solve
      new_nodes.push_back(entry.node);
    }
  try {
    SolveForNewNodes(new_nodes);
  } catch (...) {
    for (int node : new_nodes) slot_of_node_[node] = -1;  // not held: solved again next time
    throw;
  }
  for (GroupEntry& entry : entries) {
    entry.G = CalcNodeRotation(entry.node, element_rotations).transpose() * entry.G;
    entry.block = 3 * slot_of_node_[entry.node];
  }
  Eigen::MatrixXd W(J_u.rows(), J_u.rows());
  for (const RowGroup& h : groups)
    for (const RowGroup* g = &h; g != groups.data() + groups.size(); ++g)
      W.block(g->first_row, h.first_row, g->num_rows, h.num_rows) =
          CalcGroupBlock(*g, h, entries, held_compliance_).topLeftCorner(g->num_rows, h.num_rows);
  // The upper triangle in one pass: writing each block's transpose as it comes strides across
  // all of W's columns (1.8 against 1.3 ms a frame on block_press_friction).
  W.triangularView<Eigen::StrictlyUpper>() = W.transpose();
  return W;
}

}  // namespace hapsim::fem
