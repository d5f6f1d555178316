// The visual frame's moving rigid objects (contact/visual_frame.h): scripted motion, and paper
// 003's selection and grabbing.
#include <Eigen/Geometry>

#include "contact/visual_frame.h"

namespace hapsim::contact {

void VisualFrame::MoveRigidObjects(bool button_down, bool pressed, const ToolState& tool) {
  const double t_start_s = static_cast<double>(frame_index_) * options_.dt_s;
  const double t_end_s = t_start_s + options_.dt_s;
  object_motion_.assign(rigid_contacts_.num_objects(), ObjectMotion{});
  for (int i = 0; i < rigid_contacts_.num_objects(); ++i) {
    const RigidObject& object = rigid_contacts_.object(i);
    if (!object.script) continue;
    const Eigen::Isometry3d X_start = CalcScriptedPose(object, t_start_s);
    const Eigen::Isometry3d X_end = CalcScriptedPose(object, t_end_s);
    // The mean velocity over the frame carries each point to its end pose: exactly for a
    // translation, to first order in the angle for a turn.
    ObjectMotion& motion = object_motion_[i];
    motion.x_W_m = X_start.translation();
    motion.v_W_m_s = (X_end.translation() - X_start.translation()) / options_.dt_s;
    motion.w_W_rad_s =
        CalcRotationVector(Eigen::Quaterniond(X_end.linear() * X_start.linear().transpose())) /
        options_.dt_s;
    rigid_contacts_.SetMotion(i, X_start, X_end);
  }
  // Grabbing acts on a press (the button going down), so holding it while touching an object
  // does not pick the object up; releasing lets go: a fixed object stays where it is, a dynamic
  // one leaves with the tool's motion and falls.
  const Eigen::Isometry3d X_WT = CalcPose(tool);
  if (grabbed_object() >= 0 && !button_down) {
    if (DynamicObject* dynamic = FindDynamicObject(grabbed_object()))
      LetGo(rigid_contacts_.pose(grabbed_object()), tool.x_W_m, tool.v_W_m_s,
            CalcAngularVelocity(tool_, tool), dynamic);
    rigid_contacts_.SetGrabbed(-1);
  }
  if (pressed && grabbed_object() < 0 && selected_object_ >= 0) {
    X_TO_grabbed_ = X_WT.inverse() * rigid_contacts_.pose(selected_object_);
    rigid_contacts_.SetGrabbed(selected_object_, X_TO_grabbed_);
  }
  if (grabbed_object() >= 0) rigid_contacts_.SetPose(grabbed_object(), X_WT * X_TO_grabbed_);
  // Dynamic objects: the free step under gravity, placed at the frame's start and swept to where
  // it would take them (their motion enters the rows through their own Jacobian, not
  // object_motion_, which stays zero for them until the frame's end).
  for (DynamicObject& object : dynamic_objects_) {
    if (!IsFreeDynamicObject(object.object)) continue;
    StartFreeStep(options_.gravity_m_s2, options_.dt_s, &object);
    rigid_contacts_.SetMotion(object.object, CalcPose(object.state),
                              CalcFreeEndPose(object, options_.dt_s));
  }
}

DynamicObject* VisualFrame::FindDynamicObject(int i) {
  for (DynamicObject& object : dynamic_objects_)
    if (object.object == i) return &object;
  return nullptr;
}

// A row measures (velocity of the body side − velocity of the tool side)·direction
// (contact/contact_jacobian.h). A moving object is the body side of a tool contact and the tool
// side of a body-node contact: w = ±v_O(p); of two objects touching, rigid_object is the tool side
// and other_object the body side. The grabbed object moves with the tool, through J_v and J_ω; a
// dynamic object's motion is zero here during its frame's solve (its rows carry it).
void VisualFrame::CalcObjectVelocities() {
  const auto velocity_at = [&](int object, const Eigen::Vector3d& p_W_m) {
    const ObjectMotion& motion = object_motion_[object];
    return Eigen::Vector3d(motion.v_W_m_s + motion.w_W_rad_s.cross(p_W_m - motion.x_W_m));
  };
  object_velocity_.assign(contacts_.size(), Eigen::Vector3d::Zero());
  for (size_t i = 0; i < contacts_.size(); ++i) {
    const Contact& contact = contacts_[i];
    Eigen::Vector3d& w = object_velocity_[i];
    const int object = contact.rigid_object;
    if (object >= 0 && object != grabbed_object()) {
      if (contact.on_tool)
        w += velocity_at(object, contact.p_body_W_m);
      else
        w -= velocity_at(object, contact.p_tool_W_m);
    }
    const int other = contact.other_object;
    if (other >= 0 && other != grabbed_object()) w += velocity_at(other, contact.p_body_W_m);
  }
}

// The rows' directions are those of each contact's own normal (its tangents from CalcTangents),
// so the linear model's contacts, whose normals turned with the haptic tool, get theirs.
Eigen::VectorXd VisualFrame::CalcObjectSeparatingVelocity(
    const std::vector<Contact>& contacts) const {
  Eigen::VectorXd c = Eigen::VectorXd::Zero(rows_per_contact_ * static_cast<int>(contacts.size()));
  for (size_t i = 0; i < contacts.size(); ++i) {
    const Eigen::Vector3d& w = object_velocity_[i];
    if (w.isZero(0.0)) continue;
    Eigen::Vector3d directions[3] = {contacts[i].n_W, Eigen::Vector3d::Zero(),
                                     Eigen::Vector3d::Zero()};
    if (rows_per_contact_ == 3) CalcTangents(contacts[i].n_W, &directions[1], &directions[2]);
    for (int d = 0; d < rows_per_contact_; ++d)
      c[rows_per_contact_ * static_cast<int>(i) + d] = directions[d].dot(w);
  }
  return c;
}

void VisualFrame::FinishRigidObjects(const ToolState& tool) {
  const double t_end_s = static_cast<double>(frame_index_ + 1) * options_.dt_s;
  for (int i = 0; i < rigid_contacts_.num_objects(); ++i)
    if (rigid_contacts_.object(i).script)
      rigid_contacts_.SetPose(i, CalcScriptedPose(rigid_contacts_.object(i), t_end_s));
  // Dynamic objects step with the impulses; from here on (the linear model's targets, the sanity
  // pass) their velocity after the frame is their motion, as a scripted object's is.
  for (DynamicObject& object : dynamic_objects_) {
    if (!IsFreeDynamicObject(object.object)) continue;
    FinishObjectStep(lambda_, options_.dt_s, &object);
    rigid_contacts_.SetPose(object.object, CalcPose(object.state));
    ObjectMotion& motion = object_motion_[object.object];
    motion.x_W_m = object.state.x_W_m;
    motion.v_W_m_s = object.state.v_W_m_s;
    motion.w_W_rad_s = CalcAngularVelocity(object.model, object.state);
  }
  if (!dynamic_objects_.empty()) CalcObjectVelocities();
  const int grabbed = grabbed_object();
  if (grabbed >= 0) {
    rigid_contacts_.SetPose(grabbed, CalcPose(tool) * X_TO_grabbed_);
    selected_object_ = grabbed;
    return;
  }
  // Touching selects: the grabbable object of the tool contact nearest at the frame's end, if it
  // is within the detection margin.
  selected_object_ = -1;
  double nearest_m = options_.detection.margin_m;
  for (size_t i = 0; i < contacts_.size(); ++i) {
    const Contact& contact = contacts_[i];
    if (!contact.on_tool || contact.rigid_object < 0) continue;
    if (!rigid_contacts_.object(contact.rigid_object).grabbable) continue;
    const double gap_end_m =
        contact.gap_m + options_.dt_s * c_post_[rows_per_contact_ * static_cast<int>(i)];
    if (gap_end_m > nearest_m) continue;
    nearest_m = gap_end_m;
    selected_object_ = contact.rigid_object;
  }
}

Eigen::Vector3d VisualFrame::CalcObjectPointVelocity(int i, const Eigen::Vector3d& p_W_m,
                                                     const ToolState& tool) const {
  if (i < 0 || i >= static_cast<int>(object_motion_.size())) return Eigen::Vector3d::Zero();
  if (i == grabbed_object())
    return tool.v_W_m_s + CalcAngularVelocity(tool_, tool).cross(p_W_m - tool.x_W_m);
  // About where the object is now (the sanity pass runs at the frame's end).
  const ObjectMotion& motion = object_motion_[i];
  return motion.v_W_m_s + motion.w_W_rad_s.cross(p_W_m - rigid_contacts_.pose(i).translation());
}

}  // namespace hapsim::contact
