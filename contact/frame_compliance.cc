#include "contact/frame_compliance.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

namespace hapsim::contact {

void FrameCompliance::Reset(Eigen::Index rows) {
  warped_ = nullptr;
  base_ = nullptr;
  parts_.clear();
  formed_.assign(static_cast<size_t>(rows), 0);
}

void FrameCompliance::SetWhole(Eigen::MatrixXd W) {
  Reset(W.rows());
  W_ = std::move(W);
  diagonal_ = W_.diagonal();
}

void FrameCompliance::SetByColumns(const fem::WarpedCompliance* warped, Eigen::Index rows) {
  Reset(rows);
  warped_ = warped;
  W_.resize(rows, rows);  // columns are written as they are formed
  diagonal_ = warped->CalcDiagonal();
}

void FrameCompliance::SetAbove(FrameCompliance* base) {
  const Eigen::Index rows = base->W().rows();
  Reset(rows);
  if (base->is_whole()) {
    W_ = base->W();
  } else {
    base_ = base;
    W_.resize(rows, rows);
  }
  diagonal_ = base->diagonal();
}

void FrameCompliance::AddRigidPart(const ContactJacobian& J, const ToolStepSystem& system) {
  if (warped_ != nullptr) {
    const Eigen::Matrix3d S_v = system.A_v.inverse();
    const Eigen::Matrix3d S_L = system.M_inv_W * system.A_L.inverse();
    if (!S_v.isApprox(S_v.transpose(), 1e-12) || !S_L.isApprox(S_L.transpose(), 1e-12))
      throw std::invalid_argument(
          "FrameCompliance::AddRigidPart: an unsymmetric part on the warped compliance's columns "
          "(add it above them, SetAbove)");
  }
  ToolDelassusColumns part(J, system);
  part.AddDiagonal(&diagonal_);
  if (is_whole())
    part.AddAll(&W_);
  else
    parts_.push_back(std::move(part));
}

void FrameCompliance::Fill(const std::vector<Eigen::Index>& columns) {
  if (is_whole()) return;
  to_form_.clear();
  for (Eigen::Index c : columns)
    if (!formed_[c]) to_form_.push_back(c);
  std::sort(to_form_.begin(), to_form_.end());
  to_form_.erase(std::unique(to_form_.begin(), to_form_.end()), to_form_.end());
  if (to_form_.empty()) return;
  if (warped_ != nullptr) {
    // The body's columns take their rows at the columns formed before from those (W_body is
    // symmetric), parts included: the parts are added only at the other rows.
    formed_before_ = formed_;
    warped_->CalcColumns(to_form_, &W_, &formed_);  // marks them formed
    for (const ToolDelassusColumns& part : parts_)
      for (Eigen::Index c : to_form_) part.AddColumn(c, &W_, &formed_before_);
    return;
  }
  base_->Fill(to_form_);
  for (Eigen::Index c : to_form_) {
    formed_[c] = 1;
    W_.col(c) = base_->W().col(c);
    for (const ToolDelassusColumns& part : parts_) part.AddColumn(c, &W_);
  }
}

void FrameCompliance::WriteDiagonalOfUnformedColumns() {
  if (is_whole()) return;
  for (Eigen::Index c = 0; c < W_.cols(); ++c)
    if (!formed_[c]) W_(c, c) = diagonal_[c];
}

Eigen::Index FrameCompliance::num_formed() const {
  if (is_whole()) return W_.cols();
  return static_cast<Eigen::Index>(std::count(formed_.begin(), formed_.end(), 1));
}

}  // namespace hapsim::contact
