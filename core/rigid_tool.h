#pragma once
// The rigid tool (DESIGN.md §3): an immutable ToolModel (shape, mass, body inertia) apart from
// the ToolState (centre-of-mass position and velocity, orientation, angular momentum).
//
// Frames: W world (z up), T tool (origin at the centre of mass, see tool_shape.h). q_WT rotates
// tool-frame vectors into the world: v_W = R(q_WT) v_T. The state carries the angular momentum
// L (world) rather than ω because L is what torque integrates (dL/dt = T) and it is conserved
// exactly by a torque-free step; ω = M⁻¹ L with the world inverse inertia M⁻¹ = R I_b⁻¹ Rᵀ.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/tool_shape.h"

namespace hapsim {

struct ToolModel {
  ToolShape shape;  // in frame T (a mesh is re-centred on its centre of mass)
  double mass_kg = 0.0;
  Eigen::Matrix3d inertia_T_kg_m2 = Eigen::Matrix3d::Zero();  // body inertia about the COM, T
};

// Mass properties from a uniform density (CalcMassProperties). A mesh's vertices are translated
// so that the centre of mass is the origin of T; its axes are kept (the inertia may be full).
// Throws std::invalid_argument as CalcMassProperties does.
ToolModel MakeToolModel(ToolShape shape, double density_kg_m3);

// Same, with the total mass given: the density is whatever yields mass_kg (inertia scaled by
// mass_kg / mass at unit density). Throws std::invalid_argument if mass_kg ≤ 0.
ToolModel MakeToolModelWithMass(ToolShape shape, double mass_kg);

struct ToolState {
  Eigen::Vector3d x_W_m = Eigen::Vector3d::Zero();           // centre of mass, world, m
  Eigen::Vector3d v_W_m_s = Eigen::Vector3d::Zero();         // COM velocity, world, m/s
  Eigen::Quaterniond q_WT = Eigen::Quaterniond::Identity();  // orientation, unit
  Eigen::Vector3d L_W_kg_m2_s = Eigen::Vector3d::Zero();     // angular momentum about COM, world
};

// World inverse inertia M⁻¹ = R I_b⁻¹ Rᵀ, R = R(q_WT) (1/(kg m²)).
Eigen::Matrix3d CalcWorldInverseInertia(const ToolModel& model, const Eigen::Quaterniond& q_WT);

// Angular velocity ω = M⁻¹ L, world, rad/s.
Eigen::Vector3d CalcAngularVelocity(const ToolModel& model, const ToolState& state);

// Pose X_WT of the tool frame in the world.
Eigen::Isometry3d CalcPose(const ToolState& state);

// Kinetic energy ½ m |v|² + ½ Lᵀ M⁻¹ L, J.
double CalcKineticEnergy(const ToolModel& model, const ToolState& state);

// Exponential map of SO(3) as a unit quaternion: the rotation by |φ| about φ/|φ| (φ in rad),
// q = (cos(|φ|/2), sin(|φ|/2) φ/|φ|), with the Taylor series of sin(|φ|/2)/|φ| near 0.
Eigen::Quaterniond CalcQuaternionExp(const Eigen::Vector3d& phi_rad);

}  // namespace hapsim
