#include "core/rigid_tool.h"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace hapsim {

ToolModel MakeToolModel(ToolShape shape, double density_kg_m3) {
  const MassProperties props = CalcMassProperties(shape, density_kg_m3);
  if (shape.kind == ToolShape::Kind::kMesh) {
    shape.mesh.vertices_m.colwise() -= props.com_m;  // frame T: origin at the COM
  }
  ToolModel model;
  model.shape = std::move(shape);
  model.mass_kg = props.mass_kg;
  model.inertia_T_kg_m2 = props.inertia_com_kg_m2;
  return model;
}

ToolModel MakeToolModelWithMass(ToolShape shape, double mass_kg) {
  if (!(std::isfinite(mass_kg) && mass_kg > 0.0)) {
    throw std::invalid_argument("MakeToolModelWithMass: mass must be positive");
  }
  ToolModel model = MakeToolModel(std::move(shape), 1.0);
  const double scale = mass_kg / model.mass_kg;  // mass and inertia are linear in the density
  model.mass_kg = mass_kg;
  model.inertia_T_kg_m2 *= scale;
  return model;
}

Eigen::Matrix3d CalcWorldInverseInertia(const ToolModel& model, const Eigen::Quaterniond& q_WT) {
  const Eigen::Matrix3d R_WT = q_WT.toRotationMatrix();
  return R_WT * model.inertia_T_kg_m2.inverse() * R_WT.transpose();
}

Eigen::Vector3d CalcAngularVelocity(const ToolModel& model, const ToolState& state) {
  return CalcWorldInverseInertia(model, state.q_WT) * state.L_W_kg_m2_s;
}

Eigen::Isometry3d CalcPose(const ToolState& state) {
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();
  X_WT.linear() = state.q_WT.toRotationMatrix();
  X_WT.translation() = state.x_W_m;
  return X_WT;
}

double CalcKineticEnergy(const ToolModel& model, const ToolState& state) {
  const Eigen::Vector3d w_W_rad_s = CalcAngularVelocity(model, state);
  return 0.5 * model.mass_kg * state.v_W_m_s.squaredNorm() + 0.5 * state.L_W_kg_m2_s.dot(w_W_rad_s);
}

Eigen::Quaterniond CalcQuaternionExp(const Eigen::Vector3d& phi_rad) {
  const double angle = phi_rad.norm();
  const double half = 0.5 * angle;
  // sin(|φ|/2)/|φ| = ½ (1 − h²/6 + h⁴/120 − …), h = |φ|/2; the series is exact to rounding
  // below h = 1e-4 (next term h⁶/5040 ~ 1e-28).
  const double sin_half_over_angle =
      half < 1e-4 ? 0.5 * (1.0 - half * half / 6.0 + half * half * half * half / 120.0)
                  : std::sin(half) / angle;
  const Eigen::Vector3d xyz = sin_half_over_angle * phi_rad;
  return Eigen::Quaterniond(std::cos(half), xyz.x(), xyz.y(), xyz.z());
}

}  // namespace hapsim
