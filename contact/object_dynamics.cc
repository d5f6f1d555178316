#include "contact/object_dynamics.h"

#include <Eigen/LU>
#include <stdexcept>

namespace hapsim::contact {
namespace {

// Its angular velocity ω = M⁻¹ L, world, after the free step (free) or now (M⁻¹ frozen at the
// step's start).
Eigen::Vector3d CalcObjectAngularVelocity(const DynamicObject& object, bool free) {
  const Eigen::Vector3d L =
      object.state.L_W_kg_m2_s + (free ? object.dL_W_kg_m2_s : Eigen::Vector3d::Zero());
  return object.system.M_inv_W * L;
}

}  // namespace

DynamicObject MakeDynamicObject(int index, const RigidObject& object) {
  if (!object.dynamic)
    throw std::invalid_argument("MakeDynamicObject: " + object.name + " is not dynamic");
  if (!(object.mass_kg > 0.0))
    throw std::invalid_argument("MakeDynamicObject: " + object.name + " has no mass");
  DynamicObject dynamic;
  dynamic.object = index;
  dynamic.model.shape = object.shape;
  dynamic.model.mass_kg = object.mass_kg;
  dynamic.model.inertia_T_kg_m2 = object.inertia_O_kg_m2;
  dynamic.state.x_W_m = object.X_WO.translation();
  dynamic.state.q_WT = Eigen::Quaterniond(object.X_WO.linear());
  return dynamic;
}

void StartFreeStep(const Eigen::Vector3d& gravity_m_s2, double dt_s, DynamicObject* object) {
  object->system =
      CalcToolStepSystem(object->model, object->state, CouplingWrench{}, gravity_m_s2, dt_s);
  CalcFreeVelocityChange(object->system, &object->dv_W_m_s, &object->dL_W_kg_m2_s);
}

Eigen::Isometry3d CalcFreeEndPose(const DynamicObject& object, double dt_s) {
  ToolState end = object.state;
  AdvanceTool(object.model, dt_s, object.dv_W_m_s, object.dL_W_kg_m2_s, &end);
  return CalcPose(end);
}

void SetObjectRows(const std::vector<Contact>& contacts, int rows_per_contact,
                   DynamicObject* object) {
  const int num_rows = rows_per_contact * static_cast<int>(contacts.size());
  ContactJacobian& J = object->J;
  J.rows_per_contact = rows_per_contact;
  J.J_v.setZero(num_rows, 3);
  J.J_w.setZero(num_rows, 3);
  J.J_u.resize(num_rows, 0);
  for (size_t i = 0; i < contacts.size(); ++i) {
    const Contact& contact = contacts[i];
    // The object's side of the row (contact/contact.h): the body side of a tool contact and of an
    // object–object contact's other_object; the tool side of a body node's contact and of an
    // object–object contact's rigid_object.
    double sign = 0.0;
    Eigen::Vector3d p_W_m;
    if (contact.other_object == object->object) {
      sign = 1.0;
      p_W_m = contact.p_body_W_m;
    } else if (contact.rigid_object == object->object) {
      sign = contact.on_tool ? 1.0 : -1.0;
      p_W_m = contact.on_tool ? contact.p_body_W_m : contact.p_tool_W_m;
    } else {
      continue;
    }
    Eigen::Vector3d directions[3] = {contact.n_W, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    if (rows_per_contact == 3) CalcTangents(contact.n_W, &directions[1], &directions[2]);
    const Eigen::Vector3d r_W_m = p_W_m - object->state.x_W_m;
    for (int d = 0; d < rows_per_contact; ++d) {
      const int row = rows_per_contact * static_cast<int>(i) + d;
      J.J_v.row(row) = sign * directions[d].transpose();
      J.J_w.row(row) = sign * r_W_m.cross(directions[d]).transpose();
    }
  }
}

void AddObjectSeparatingVelocity(const DynamicObject& object, bool free, Eigen::VectorXd* c) {
  const Eigen::Vector3d v =
      object.state.v_W_m_s + (free ? object.dv_W_m_s : Eigen::Vector3d::Zero());
  *c += object.J.J_v * v + object.J.J_w * CalcObjectAngularVelocity(object, free);
}

void FinishObjectStep(const Eigen::VectorXd& lambda_N, double dt_s, DynamicObject* object) {
  // A Δv = Δt (F̃ + J_vᵀλ): the free change plus the impulses' (A_v = m I, A_L = I here).
  object->dv_W_m_s +=
      object->system.A_v.partialPivLu().solve(dt_s * (object->J.J_v.transpose() * lambda_N));
  object->dL_W_kg_m2_s +=
      object->system.A_L.partialPivLu().solve(dt_s * (object->J.J_w.transpose() * lambda_N));
  AdvanceTool(object->model, dt_s, object->dv_W_m_s, object->dL_W_kg_m2_s, &object->state);
}

void LetGo(const Eigen::Isometry3d& X_WO, const Eigen::Vector3d& x_tool_W_m,
           const Eigen::Vector3d& v_tool_W_m_s, const Eigen::Vector3d& w_tool_W_rad_s,
           DynamicObject* object) {
  ToolState& state = object->state;
  state.x_W_m = X_WO.translation();
  state.q_WT = Eigen::Quaterniond(X_WO.linear());
  state.v_W_m_s = v_tool_W_m_s + w_tool_W_rad_s.cross(state.x_W_m - x_tool_W_m);
  // L = M ω with the world inertia M = R I_b Rᵀ.
  const Eigen::Matrix3d R = X_WO.linear();
  state.L_W_kg_m2_s = R * object->model.inertia_T_kg_m2 * R.transpose() * w_tool_W_rad_s;
}

double CalcObjectEnergy(const DynamicObject& object, const Eigen::Vector3d& gravity_m_s2) {
  return CalcKineticEnergy(object.model, object.state) -
         object.model.mass_kg * gravity_m_s2.dot(object.state.x_W_m);
}

}  // namespace hapsim::contact
