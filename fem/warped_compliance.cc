#include "fem/warped_compliance.h"

#include <algorithm>
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

Eigen::MatrixXd WarpedCompliance::Calc(const Eigen::SparseMatrix<double>& J_u,
                                       const std::vector<Eigen::Matrix3d>& element_rotations) {
  // Per row, the nodes it touches with j, its 3 entries there. J_uᵀ is column-major with sorted
  // rows, so its column r lists row r's entries node by node.
  struct Entry {
    int node;
    Eigen::Vector3d g;  // j, then R_nᵀ j: the entries in the node's rotated frame
    int block = 0;      // 3 · the node's slot: its rows and columns in held_compliance_
  };
  const Eigen::Index rows = J_u.rows();
  const Eigen::SparseMatrix<double> Jt = J_u.transpose();
  std::vector<std::vector<Entry>> entries(rows);
  std::vector<int> new_nodes;
  for (Eigen::Index r = 0; r < rows; ++r)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Jt, r); it; ++it) {
      const int node = static_cast<int>(it.row() / 3);
      if (entries[r].empty() || entries[r].back().node != node)
        entries[r].push_back({node, Eigen::Vector3d::Zero()});
      entries[r].back().g[it.row() % 3] = it.value();
      if (slot_of_node_[node] == -1) {
        slot_of_node_[node] = -2;  // queued for this frame's solve
        new_nodes.push_back(node);
      }
    }
  try {
    SolveForNewNodes(new_nodes);
  } catch (...) {
    for (int node : new_nodes) slot_of_node_[node] = -1;  // not held: solved again next time
    throw;
  }
  for (auto& row : entries)
    for (Entry& entry : row) {
      entry.g = CalcNodeRotation(entry.node, element_rotations).transpose() * entry.g;
      entry.block = 3 * slot_of_node_[entry.node];
    }
  Eigen::MatrixXd W(rows, rows);
  for (Eigen::Index c = 0; c < rows; ++c)
    for (Eigen::Index r = c; r < rows; ++r) {
      double sum = 0.0;
      for (const Entry& b : entries[c])
        for (const Entry& a : entries[r])
          sum += a.g.dot(held_compliance_.block<3, 3>(a.block, b.block) * b.g);  // C₀_ab
      W(r, c) = W(c, r) = sum;
    }
  return W;
}

}  // namespace hapsim::fem
