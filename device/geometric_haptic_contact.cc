#include "device/geometric_haptic_contact.h"

#include <algorithm>
#include <stdexcept>

#include "contact/tool_distance.h"

namespace hapsim::device {

GeometricHapticContact::GeometricHapticContact(HapticMode mode,
                                               const GeometricContactParams& params,
                                               const ToolModel& tool, const fem::Model* body,
                                               const std::vector<contact::RigidObject>& objects)
    : mode_(mode),
      tool_(tool),
      search_margin_m_(params.search_margin_m),
      bounding_radius_m_(contact::ToolDistanceField(tool.shape).bounding_radius_m()),
      finder_(body, tool.shape, objects, params.search_margin_m),
      penalty_(params.penalty, static_cast<int>(objects.size())),
      material_(params.material, static_cast<int>(objects.size())),
      impact_(params.impact) {
  if (!IsGeometricMode(mode)) {
    throw std::invalid_argument(std::string("GeometricHapticContact: not a geometric mode: ") +
                                ToString(mode));
  }
  for (const contact::RigidObject& object : objects) object_poses_.push_back(object.X_WO);
  contacts_.reserve(static_cast<size_t>(std::max(params.max_contacts, 1)));
}

void GeometricHapticContact::SetWorld(const Eigen::VectorXd& x_body_m,
                                      const std::vector<Eigen::Isometry3d>& X_WO) {
  finder_.SetBodyPositions(x_body_m);
  for (size_t i = 0; i < X_WO.size() && i < object_poses_.size(); ++i) {
    object_poses_[i] = X_WO[i];
    finder_.SetObjectPose(static_cast<int>(i), X_WO[i]);
  }
}

void GeometricHapticContact::Calc(const ToolStepSystem& system, const ToolState& state,
                                  Eigen::Vector3d* F_W_N, Eigen::Vector3d* T_W_N_m) {
  const Eigen::Isometry3d X_WT = CalcPose(state);
  const Eigen::Vector3d w_W = CalcAngularVelocity(tool_, state);
  switch (mode_) {
    case HapticMode::kPenalty: {
      // ε = v Δt, capped by how far the finder searches (a non-finite state gives none).
      double margin_m = penalty_.CalcMargin(state.v_W_m_s, w_W, bounding_radius_m_, system.dt_s);
      margin_m = margin_m >= 0.0 ? std::min(margin_m, search_margin_m_) : 0.0;
      finder_.Find(X_WT, margin_m, &contacts_);
      penalty_.Calc(contacts_, margin_m, state.x_W_m, F_W_N, T_W_N_m);
      return;
    }
    case HapticMode::kMaterial:
      finder_.Find(X_WT, 0.0, &contacts_);
      material_.Calc(contacts_, X_WT, state.v_W_m_s, object_poses_, F_W_N, T_W_N_m);
      return;
    case HapticMode::kImpact:
      // Every contact the free step could close: the search margin bounds |s| Δt.
      finder_.Find(X_WT, search_margin_m_, &contacts_);
      impact_.Calc(contacts_, system, tool_, state, F_W_N, T_W_N_m);
      return;
    default:
      F_W_N->setZero();
      T_W_N_m->setZero();
  }
}

}  // namespace hapsim::device
