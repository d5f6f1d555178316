#pragma once
// A visual frame's Delassus matrix, or its body part, formed whole or column by column as the
// frame's readers ask for columns (DESIGN.md §4):
//
//   W_body = J_u A_u⁻¹ J_uᵀ + Σ_o J_o S_o J_oᵀ          (the body, and each free dynamic object)
//   W      = W_body + [J_v J_ω] S [J_v J_ω]ᵀ            (and the tool: the frame's solve)
//
// Under the unilateral law every reader of W needs only some of its columns: the solve those of
// the rows it loads (SolveUnilateralByColumns), the linear model the active rows', the lcp rows
// the coupled rows' and the others' own entries. On block_press's frames with ≥ 200 contacts 68 of
// 216 rows carry load, so the solve forms a third of the columns, each a pass over the held C₀ of
// the warped compliance; the model handed to the haptic step forms its coupled rows' columns, 74
// in the hybrid mode (~175 before the eighth pass of docs/BENCHMARKS.md, issue 25).
//
// Formed columns are whole (every row), so W(r, c) of a formed column c is right whatever r is;
// the diagonal is formed for every row at the start, without a pass over C₀.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "contact/contact_jacobian.h"
#include "contact/linear_contact_model.h"
#include "fem/warped_compliance.h"

namespace hapsim::contact {

class FrameCompliance {
 public:
  // W given whole (the exact compliance, friction rows, a frame without a body).
  void SetWhole(Eigen::MatrixXd W);
  // The body's W_body by columns from `warped`, whose rows are the frame's (after its SetRows).
  // `warped` must outlive this frame's use of it.
  void SetByColumns(const fem::WarpedCompliance* warped, Eigen::Index rows);
  // W = base + the parts added below, by columns as `base` is (base must outlive its use).
  void SetAbove(FrameCompliance* base);
  // Adds a rank-6 part, a rigid body's (a free dynamic object's) or the tool's: at once when
  // whole, else to each column formed from now on (call before the first Fill). By columns from
  // the warped compliance, whose columns take their rows at earlier columns from those by
  // symmetry, the part must be symmetric (S = blockdiag(A_v⁻¹, M⁻¹A_L⁻¹) is: a free body's, with
  // no coupling torque); a tool's, unsymmetric under a coupling torque, goes above it (SetAbove).
  // Throws std::invalid_argument for an unsymmetric part there.
  void AddRigidPart(const ContactJacobian& J, const ToolStepSystem& system);

  // Forms those of `columns` not formed yet (nothing to do when whole).
  void Fill(const std::vector<Eigen::Index>& columns);
  // Writes W(c, c) into every column c not formed, for readers of a row's own entry only.
  void WriteDiagonalOfUnformedColumns();

  bool is_whole() const { return warped_ == nullptr && base_ == nullptr; }
  bool has_column(Eigen::Index c) const { return is_whole() || formed_[c] != 0; }
  Eigen::Index num_formed() const;
  const Eigen::MatrixXd& W() const { return W_; }  // its formed columns
  const Eigen::VectorXd& diagonal() const { return diagonal_; }

 private:
  void Reset(Eigen::Index rows);

  const fem::WarpedCompliance* warped_ = nullptr;  // by columns from the warped compliance, or
  FrameCompliance* base_ = nullptr;                // by columns from another's (null both: whole)
  std::vector<ToolDelassusColumns> parts_;
  Eigen::MatrixXd W_;
  Eigen::VectorXd diagonal_;
  std::vector<std::uint8_t> formed_, formed_before_;
  std::vector<Eigen::Index> to_form_;
};

}  // namespace hapsim::contact
