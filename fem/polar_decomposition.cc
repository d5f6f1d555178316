#include "fem/polar_decomposition.h"

#include <Eigen/Dense>
#include <cmath>

namespace hapsim::fem {
namespace {

// Below this det F / (‖F‖_F/√3)³ the Newton iteration is slow or meaningless (flat or inverted).
constexpr double kMinRelativeDeterminant = 1e-3;
constexpr int kMaxNewtonIterations = 20;
// Convergence is quadratic: once a step moves X by less than 1e-8 (X of unit scale), the error
// left after it is of order (1e-8)² = 1e-16, i.e. round-off.
constexpr double kNewtonStepTolerance = 1e-6;
// Near convergence det X → 1 and the scaling γ → 1; skipping it there saves a cube root and
// keeps quadratic convergence.
constexpr double kSkipScalingDeterminantBand = 1e-3;

Eigen::Matrix3d CalcRotationBySvd(const Eigen::Matrix3d& F) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d U = svd.matrixU();
  // Singular values are sorted in decreasing order: flip the last column for a proper rotation.
  if ((U * svd.matrixV().transpose()).determinant() < 0.0) U.col(2) *= -1.0;
  return U * svd.matrixV().transpose();
}

// X⁻ᵀ = cof(X) / det X, with cof the cofactor matrix.
Eigen::Matrix3d CalcCofactor(const Eigen::Matrix3d& X) {
  Eigen::Matrix3d C;
  C.col(0) = X.col(1).cross(X.col(2));
  C.col(1) = X.col(2).cross(X.col(0));
  C.col(2) = X.col(0).cross(X.col(1));
  return C;
}

}  // namespace

Eigen::Matrix3d CalcRotationOfDeformation(const Eigen::Matrix3d& F) {
  const double scale = F.norm() / std::sqrt(3.0);
  if (!(scale > 0.0) || !std::isfinite(scale)) return Eigen::Matrix3d::Identity();
  Eigen::Matrix3d X = F * (1.0 / scale);  // one division, not nine
  if (X.determinant() < kMinRelativeDeterminant) return CalcRotationBySvd(F);
  for (int iteration = 0; iteration < kMaxNewtonIterations; ++iteration) {
    const Eigen::Matrix3d cofactor = CalcCofactor(X);
    const double det = X.col(0).dot(cofactor.col(0));
    const double gamma =
        std::abs(det - 1.0) < kSkipScalingDeterminantBand ? 1.0 : std::cbrt(1.0 / det);
    const Eigen::Matrix3d next = (0.5 * gamma) * X + (0.5 / (gamma * det)) * cofactor;
    const double change_sq = (next - X).squaredNorm();
    X = next;
    if (change_sq < kNewtonStepTolerance * kNewtonStepTolerance) return X;
  }
  return CalcRotationBySvd(F);
}

}  // namespace hapsim::fem
