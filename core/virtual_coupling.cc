#include "core/virtual_coupling.h"

#include <cmath>

namespace hapsim {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d S;
  S << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return S;
}

}  // namespace

Eigen::Vector3d CalcRotationVector(const Eigen::Quaterniond& q_in) {
  const double sign = q_in.w() < 0.0 ? -1.0 : 1.0;  // shortest rotation: w ≥ 0
  const double w = sign * q_in.w();
  const Eigen::Vector3d u = sign * q_in.vec();
  const double s = u.norm();
  // θ = 2 atan2(s, w)/s · u. For s → 0 (then w → 1): 2 atan(s/w)/s = (2/w)(1 − s²/(3w²) + …),
  // error O(s⁴) < 1e-32 below s = 1e-8.
  const double scale =
      s < 1e-8 ? 2.0 / w * (1.0 - s * s / (3.0 * w * w)) : 2.0 * std::atan2(s, w) / s;
  return scale * u;
}

Eigen::Matrix3d CalcInverseRightJacobianSO3(const Eigen::Vector3d& theta_rad) {
  const double angle = theta_rad.norm();
  const double a2 = angle * angle;
  // 1/θ² − cot(θ/2)/(2θ); its Taylor series 1/12 + θ²/720 + θ⁴/30240 has error O(θ⁶) ~ 1e-18
  // relative at θ < 1e-3, where the closed form loses ~ 6 digits to cancellation.
  const double c = angle < 1e-3
                       ? 1.0 / 12.0 + a2 / 720.0 + a2 * a2 / 30240.0
                       : 1.0 / a2 - std::cos(0.5 * angle) / (2.0 * angle * std::sin(0.5 * angle));
  const Eigen::Matrix3d S = Skew(theta_rad);
  return Eigen::Matrix3d::Identity() + 0.5 * S + c * S * S;
}

CouplingWrench CalcCouplingWrench(const CouplingParams& params, const DeviceState& device,
                                  const ToolState& tool, const Eigen::Vector3d& w_tool_W_rad_s) {
  CouplingWrench wrench;
  // Orientation error in the world: the rotation carrying the tool onto the device.
  const Eigen::Vector3d theta_rad = CalcRotationVector(device.q_WD * tool.q_WT.conjugate());
  wrench.F_W_N = params.k_lin_N_m * (device.x_W_m - tool.x_W_m) +
                 params.b_lin_N_s_m * (device.v_W_m_s - tool.v_W_m_s);
  wrench.T_W_N_m = params.k_ang_N_m_rad * theta_rad +
                   params.b_ang_N_m_s_rad * (device.w_W_rad_s - w_tool_W_rad_s);
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  wrench.dF_dx = -params.k_lin_N_m * I;
  wrench.dF_dv = -params.b_lin_N_s_m * I;
  wrench.dT_dtheta = -params.k_ang_N_m_rad * CalcInverseRightJacobianSO3(theta_rad);
  wrench.dT_domega = -params.b_ang_N_m_s_rad * I;
  return wrench;
}

}  // namespace hapsim
