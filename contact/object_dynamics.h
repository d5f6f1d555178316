#pragma once
// Rigid objects that fall (issue 28 item 3): a rigid object with `dynamic: true` is a rigid body
// like the tool (core/rigid_tool.h), stepped by the same linearised backward Euler
// (core/tool_integrator.h) with gravity its only applied force and no coupling, so A_v = m I and
// A_L = I. It enters the visual frame's one constraint solve through the rows that touch it (the
// tool's, the body's nodes', the other objects'). A row measures the velocity of its body side
// less that of its tool side along its direction d (contact/contact_jacobian.h), so the object
// adds to a row, at its point p (lever r = p − x from the object's centre of mass x),
//
//   +d·(v + ω × r) on the row's body side,  −d·(v + ω × r) on its tool side:
//   J_v,o = ±dᵀ,  J_ω,o = ±(r × d)ᵀ.
//
// Its Delassus part J_v,o A_v⁻¹ J_v,oᵀ + J_ω,o M⁻¹ A_L⁻¹ J_ω,oᵀ (FrameCompliance::AddRigidPart,
// with the object's matrices) joins the body's compliance: it is not the tool's, so the frame's
// solve, the paper's linear contact model and the 1 kHz lcp rows all see an object that yields as
// its mass and inertia say (a rigid body has no stiffness: its part is the same at the visual and
// the haptic step). After the solve its momenta change by Δt J_v,oᵀλ and Δt J_ω,oᵀλ, as the tool's
// do. The torque-free step keeps L (world) exactly and turns ω = M⁻¹(q) L with the body, so a
// spinning object precesses as Euler's equations say without a gyroscopic term of its own.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "contact/contact.h"
#include "contact/contact_jacobian.h"
#include "contact/rigid_objects.h"
#include "core/rigid_tool.h"
#include "core/tool_integrator.h"

namespace hapsim::contact {

struct DynamicObject {
  int object = -1;  // its index among the scene's rigid objects
  ToolModel model;  // shape, mass, body inertia about its centre of mass (O's origin)
  ToolState state;  // centre of mass, velocity, orientation, angular momentum, world
  // This frame's step: the system (gravity alone), the momentum changes (free, then with the
  // contacts' impulses) and the rows that touch it.
  ToolStepSystem system;
  Eigen::Vector3d dv_W_m_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d dL_W_kg_m2_s = Eigen::Vector3d::Zero();
  ContactJacobian J;  // J_v,o and J_ω,o over the frame's rows (no J_u)
};

// Object `index` of the scene at rest at its X_WO. Throws std::invalid_argument if it is not
// dynamic or has no positive mass.
DynamicObject MakeDynamicObject(int index, const RigidObject& object);

// The free step: the system under gravity and its free momentum changes.
void StartFreeStep(const Eigen::Vector3d& gravity_m_s2, double dt_s, DynamicObject* object);

// Where the free step would leave it: its pose after the free changes (for the sweep bounds).
Eigen::Isometry3d CalcFreeEndPose(const DynamicObject& object, double dt_s);

// J_v,o and J_ω,o of `contacts` (rows_per_contact 1 or 3, directions as CalcContactJacobian's)
// for object.object, zero on the rows that do not touch it.
void SetObjectRows(const std::vector<Contact>& contacts, int rows_per_contact,
                   DynamicObject* object);

// c += J_v,o v + J_ω,o ω, with its velocities now (free = false) or after the free step.
void AddObjectSeparatingVelocity(const DynamicObject& object, bool free, Eigen::VectorXd* c);

// Applies the contact impulses to the momentum changes, then advances the state by the step.
void FinishObjectStep(const Eigen::VectorXd& lambda_N, double dt_s, DynamicObject* object);

// Let go by the tool at pose X_WO with the tool's motion (v_tool, ω_tool about x_tool): the
// object's own velocity is its centre's velocity on the tool and ω_tool.
void LetGo(const Eigen::Isometry3d& X_WO, const Eigen::Vector3d& x_tool_W_m,
           const Eigen::Vector3d& v_tool_W_m_s, const Eigen::Vector3d& w_tool_W_rad_s,
           DynamicObject* object);

// Kinetic plus gravitational potential energy, m g·(−x) + ½ m|v|² + ½ Lᵀ M⁻¹ L, J.
double CalcObjectEnergy(const DynamicObject& object, const Eigen::Vector3d& gravity_m_s2);

}  // namespace hapsim::contact
