// Virtual coupling against independent values: central finite differences of all four
// Jacobians (the rotational one by actually rotating the tool, q ← exp(δ) q) at random poses from
// tiny to near-π errors; the rotation vector against Eigen's AngleAxis; the reaction's sign; a
// zero wrench at coincident poses (for either quaternion sign).
#include "core/virtual_coupling.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/rigid_tool.h"

namespace hapsim {
namespace {

constexpr double kPi = 3.14159265358979323846;

const CouplingParams kParams = {3000.0, 2.0, 2.5, 0.01};

Eigen::Vector3d RandomUnit(std::mt19937* rng) {
  std::normal_distribution<double> normal;
  return Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng)).normalized();
}

Eigen::Vector3d RandomVector(std::mt19937* rng, double scale) {
  std::uniform_real_distribution<double> uniform(-scale, scale);
  return {uniform(*rng), uniform(*rng), uniform(*rng)};
}

// A device and a tool whose orientations differ by exactly `error_angle_rad` (random axis).
struct Scene {
  DeviceState device;
  ToolState tool;
  Eigen::Vector3d w_tool_W_rad_s;
};
Scene MakeScene(double error_angle_rad, std::mt19937* rng) {
  Scene scene;
  scene.tool.q_WT = Eigen::Quaterniond(Eigen::AngleAxisd(2.0, RandomUnit(rng)));
  scene.device.q_WD = Eigen::AngleAxisd(error_angle_rad, RandomUnit(rng)) * scene.tool.q_WT;
  scene.tool.x_W_m = RandomVector(rng, 0.1);
  scene.device.x_W_m = scene.tool.x_W_m + RandomVector(rng, 0.02);
  scene.tool.v_W_m_s = RandomVector(rng, 0.5);
  scene.device.v_W_m_s = RandomVector(rng, 0.5);
  scene.device.w_W_rad_s = RandomVector(rng, 3.0);
  scene.w_tool_W_rad_s = RandomVector(rng, 3.0);
  return scene;
}

CouplingWrench Eval(const Scene& s) {
  return CalcCouplingWrench(kParams, s.device, s.tool, s.w_tool_W_rad_s);
}

// Central differences: truncation O(h²·|f'''|) and rounding O(ε|f|/h); with h = 1e-6 rad (or
// m, m/s) both are ~1e-10 of the gain (measured ≤ 6.4e-10 up to π − 1e-3).
constexpr double kStep = 1e-6;
constexpr double kJacobianRelTol = 1e-8;

template <typename Perturb, typename Output>
Eigen::Matrix3d CentralDifference(const Scene& base, Perturb perturb, Output output) {
  Eigen::Matrix3d J;
  for (int j = 0; j < 3; ++j) {
    Scene plus = base, minus = base;
    perturb(Eigen::Vector3d::Unit(j) * kStep, &plus);
    perturb(-Eigen::Vector3d::Unit(j) * kStep, &minus);
    J.col(j) = (output(Eval(plus)) - output(Eval(minus))) / (2.0 * kStep);
  }
  return J;
}

// Returns the largest error relative to the gain (k_c or k_θ) of the four Jacobians.
double ExpectJacobiansMatchFiniteDifferences(double error_angle_rad, std::mt19937* rng) {
  const Scene scene = MakeScene(error_angle_rad, rng);
  const CouplingWrench wrench = Eval(scene);
  auto force = [](const CouplingWrench& w) { return w.F_W_N; };
  auto torque = [](const CouplingWrench& w) { return w.T_W_N_m; };
  const Eigen::Matrix3d dF_dx = CentralDifference(
      scene, [](const Eigen::Vector3d& d, Scene* s) { s->tool.x_W_m += d; }, force);
  const Eigen::Matrix3d dF_dv = CentralDifference(
      scene, [](const Eigen::Vector3d& d, Scene* s) { s->tool.v_W_m_s += d; }, force);
  const Eigen::Matrix3d dT_domega = CentralDifference(
      scene, [](const Eigen::Vector3d& d, Scene* s) { s->w_tool_W_rad_s += d; }, torque);
  const Eigen::Matrix3d dT_dtheta = CentralDifference(
      scene,
      [](const Eigen::Vector3d& d, Scene* s) {
        s->tool.q_WT = CalcQuaternionExp(d) * s->tool.q_WT;
      },
      torque);
  EXPECT_LT((dF_dx - wrench.dF_dx).norm(), kJacobianRelTol * kParams.k_lin_N_m);
  EXPECT_LT((dF_dv - wrench.dF_dv).norm(), kJacobianRelTol * kParams.k_lin_N_m);
  EXPECT_LT((dT_domega - wrench.dT_domega).norm(), kJacobianRelTol * kParams.k_ang_N_m_rad);
  EXPECT_LT((dT_dtheta - wrench.dT_dtheta).norm(), kJacobianRelTol * kParams.k_ang_N_m_rad)
      << "angle " << error_angle_rad << "\nanalytic\n"
      << wrench.dT_dtheta << "\nfinite differences\n"
      << dT_dtheta;
  return std::max({(dF_dx - wrench.dF_dx).norm() / kParams.k_lin_N_m,
                   (dF_dv - wrench.dF_dv).norm() / kParams.k_lin_N_m,
                   (dT_domega - wrench.dT_domega).norm() / kParams.k_ang_N_m_rad,
                   (dT_dtheta - wrench.dT_dtheta).norm() / kParams.k_ang_N_m_rad});
}

TEST(VirtualCouplingTest, JacobiansMatchFiniteDifferences) {
  std::mt19937 rng(7);
  // Tiny, either side of the series switch (1e-3), moderate, around π/2, large (not at π, where
  // the rotation vector jumps and no derivative exists).
  for (double angle : {0.0, 1e-7, 5e-4, 2e-3, 0.3, 1.2, kPi / 2 - 0.01, kPi / 2, kPi / 2 + 0.01,
                       2.5, 3.0, kPi - 1e-3}) {
    double worst = 0.0;
    for (int trial = 0; trial < 5; ++trial) {
      worst = std::max(worst, ExpectJacobiansMatchFiniteDifferences(angle, &rng));
    }
    std::printf("  error angle %.6g rad: max Jacobian error / gain %.2e\n", angle, worst);
  }
}

// J_r⁻¹ against the definition log(exp(θ) exp(ε)) ≈ θ + J_r⁻¹(θ) ε, differenced on quaternions.
TEST(VirtualCouplingTest, InverseRightJacobianMatchesItsDefinition) {
  std::mt19937 rng(11);
  for (double angle : {1e-6, 9.9e-4, 1.01e-3, 0.5, 2.0, 3.1}) {
    const Eigen::Vector3d theta = angle * RandomUnit(&rng);
    const Eigen::Quaterniond q = CalcQuaternionExp(theta);
    Eigen::Matrix3d J;
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(j) * kStep;
      J.col(j) = (CalcRotationVector(q * CalcQuaternionExp(e)) -
                  CalcRotationVector(q * CalcQuaternionExp(-e))) /
                 (2.0 * kStep);
    }
    EXPECT_LT((J - CalcInverseRightJacobianSO3(theta)).norm(), kJacobianRelTol) << angle;
  }
}

// θ(q) against Eigen::AngleAxis (an independent implementation), across (0, 2π): past π the
// shortest rotation is the one the other way round.
TEST(VirtualCouplingTest, RotationVectorIsTheShortestAngleAxis) {
  std::mt19937 rng(3);
  constexpr double kRotationVectorTol = 1e-14;  // a few ulps of π
  for (double angle : {0.0, 1e-12, 1e-9, 1e-5, 0.7, 2.0, kPi - 1e-9, kPi + 1e-6, 4.0, 6.2}) {
    const Eigen::Vector3d axis = RandomUnit(&rng);
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, axis));
    const double shortest = angle <= kPi ? angle : angle - 2.0 * kPi;
    EXPECT_LT((CalcRotationVector(q) - shortest * axis).norm(), kRotationVectorTol) << angle;
    const Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());  // same rotation
    EXPECT_LT((CalcRotationVector(minus_q) - shortest * axis).norm(), kRotationVectorTol);
    EXPECT_LT(CalcQuaternionExp(shortest * axis).angularDistance(q), 1e-12);
  }
}

TEST(VirtualCouplingTest, ReactionPullsTheDeviceTowardTheTool) {
  DeviceState device;
  ToolState tool;
  tool.x_W_m = Eigen::Vector3d(0.01, 0.0, 0.0);  // tool 1 cm along +x of the device
  tool.q_WT = Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()));
  const CouplingWrench w = CalcCouplingWrench(kParams, device, tool, Eigen::Vector3d::Zero());
  // On the tool: back toward the device (−x) and rotated back (−z); the device gets −F, −T.
  EXPECT_NEAR(w.F_W_N.x(), -kParams.k_lin_N_m * 0.01, 1e-12);
  EXPECT_NEAR(w.T_W_N_m.z(), -kParams.k_ang_N_m_rad * 0.2, 1e-12);
  const Eigen::Vector3d device_force_W_N = -w.F_W_N;
  EXPECT_GT(device_force_W_N.dot(tool.x_W_m - device.x_W_m), 0.0);
  // Damping: a tool moving away along +x is pulled back.
  tool.x_W_m.setZero();
  tool.v_W_m_s = Eigen::Vector3d(0.1, 0, 0);
  EXPECT_LT(CalcCouplingWrench(kParams, device, tool, Eigen::Vector3d::Zero()).F_W_N.x(), 0.0);
}

TEST(VirtualCouplingTest, ZeroWrenchAtCoincidentPoses) {
  std::mt19937 rng(5);
  Scene scene = MakeScene(0.0, &rng);
  scene.device.x_W_m = scene.tool.x_W_m;
  scene.device.v_W_m_s = scene.tool.v_W_m_s;
  scene.device.w_W_rad_s = scene.w_tool_W_rad_s;
  scene.device.q_WD = scene.tool.q_WT;
  EXPECT_EQ(Eval(scene).F_W_N, Eigen::Vector3d::Zero());
  EXPECT_LT(Eval(scene).T_W_N_m.norm(), 1e-15);
  scene.device.q_WD.coeffs() *= -1.0;  // the same orientation, the other sign
  EXPECT_LT(Eval(scene).T_W_N_m.norm(), 1e-15);
  EXPECT_LT((Eval(scene).dT_dtheta + kParams.k_ang_N_m_rad * Eigen::Matrix3d::Identity()).norm(),
            1e-15);
}

}  // namespace
}  // namespace hapsim
