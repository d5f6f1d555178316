// The rotation of a deformation gradient (fem/polar_decomposition.h) against independent values:
// the SVD polar factor, the variational characterisation R = argmax tr(RᵀF), inverted and flat
// elements; and the batched CalcRotationsOfDeformation against the scalar function, with
// fallback lanes (inverted, flat, zero, NaN) mixed into the same block as fast ones.
#include "fem/polar_decomposition.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <vector>

#include "tests/fem/test_utilities.h"

namespace hapsim::fem {
namespace {

using test::Random;

// ---------------------------------------------------------------------------------------------
// 1. CalcRotationOfDeformation: the polar factor, inverted and flat elements.

// Orthonormality and det of R. The Newton iteration stops after a step below 1e-6; with
// quadratic convergence (e⁺ ≈ e²/2) that leaves an error ≤ 5e-13 in R, so ≤ 1e-12 in RᵀR − I
// (measured worst 8.9e-13 over 2·10⁵ random F). Allow 5e-12.
constexpr double kRotationAccuracy = 5e-12;
// Symmetry of RᵀF: the Newton error is a symmetric stretch (X = R(I + E), E = Eᵀ), so the
// asymmetry is round-off only, amplified by the conditioning 2σ₁/(σ₂ + σ₃) of the polar factor
// (Higham 1986). Measured ≤ 5e-16 times that; allow 1e-12.
constexpr double kSymmetryRoundOff = 1e-12;
// Agreement with Eigen's SVD polar factor U Vᵀ: the Newton error above plus round-off of either
// method amplified by the same conditioning (measured ≤ 4.5e-13); allow kRotationAccuracy times it.
constexpr double kPolarAgreement = kRotationAccuracy;
// Eigenvalues of RᵀF against the singular values of F, relative to σ₁.
constexpr double kEigenvalueAccuracy = 1e-11;

struct PolarChecks {
  double orthonormality = 0.0;  // ‖RᵀR − I‖
  double det_error = 0.0;       // |det R − 1|
  double asymmetry = 0.0;       // ‖RᵀF − FᵀR‖ / ‖F‖
  Eigen::Vector3d eigenvalues;  // of sym(RᵀF), ascending
};

PolarChecks CheckRotation(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R) {
  PolarChecks checks;
  checks.orthonormality = (R.transpose() * R - Eigen::Matrix3d::Identity()).norm();
  checks.det_error = std::abs(R.determinant() - 1.0);
  const Eigen::Matrix3d S = R.transpose() * F;
  checks.asymmetry = (S - S.transpose()).norm() / F.norm();
  checks.eigenvalues =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(0.5 * (S + S.transpose())).eigenvalues();
  return checks;
}

// R maximises tr(RᵀF) over SO(3): no small rotation of it (R exp(W)) and no random rotation does
// better. Independent of how R was computed.
void ExpectMaximisesTrace(const Eigen::Matrix3d& F, const Eigen::Matrix3d& R, Random* random) {
  const double best = (R.transpose() * F).trace();
  const double slack = 1e-12 * F.norm();
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector3d axis =
        Eigen::Vector3d(random->Uniform(), random->Uniform(), random->Uniform()).normalized();
    for (double angle : {1e-3, 1e-1, M_PI * random->Uniform()}) {
      const Eigen::Matrix3d Q = R * Eigen::AngleAxisd(angle, axis).toRotationMatrix();
      EXPECT_LE((Q.transpose() * F).trace(), best + slack);
    }
  }
}

TEST(PolarDecomposition, PositiveDeterminantMatchesSvdPolarFactor) {
  Random random(3);
  double worst_scaled_difference = 0.0, worst_orthonormality = 0.0;
  int count = 0;
  for (int k = 0; k < 2000; ++k) {
    Eigen::Matrix3d F = random.Matrix3();
    if (k % 4 == 1) F = Eigen::Matrix3d::Identity() + 1e-3 * random.Matrix3();  // near rest
    if (k % 4 == 2) F = random.Rotation() * (Eigen::Matrix3d::Identity() + 0.3 * random.Matrix3());
    if (k % 4 == 3) F *= std::pow(10.0, 3.0 * random.Uniform());  // scale invariance
    if (F.determinant() < 0.0) F.col(0) *= -1.0;
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Vector3d sigma = svd.singularValues();
    if (sigma[2] < 1e-6 * sigma[0]) continue;  // nearly flat: covered by the sweep below
    const Eigen::Matrix3d R = CalcRotationOfDeformation(F);
    const PolarChecks checks = CheckRotation(F, R);
    EXPECT_LE(checks.orthonormality, kRotationAccuracy);
    EXPECT_LE(checks.det_error, kRotationAccuracy);
    const double conditioning = 2.0 * sigma[0] / (sigma[1] + sigma[2]);
    EXPECT_LE(checks.asymmetry, kSymmetryRoundOff * conditioning);
    EXPECT_GT(checks.eigenvalues[0], 0.0);  // RᵀF positive definite: the polar stretch
    const Eigen::Matrix3d polar = svd.matrixU() * svd.matrixV().transpose();  // det +1 here
    const double difference = (R - polar).norm();
    EXPECT_LE(difference, kPolarAgreement * conditioning) << F;
    worst_scaled_difference = std::max(worst_scaled_difference, difference / conditioning);
    worst_orthonormality = std::max(worst_orthonormality, checks.orthonormality);
    ++count;
  }
  std::printf("%d matrices: worst |R^T R - I| = %.2e, worst |R - U V^T| / cond = %.2e\n", count,
              worst_orthonormality, worst_scaled_difference);
  for (int k = 0; k < 20; ++k) {
    const Eigen::Matrix3d F =
        random.Rotation() * (Eigen::Matrix3d::Identity() + 0.4 * random.Matrix3());
    if (F.determinant() > 0.0) ExpectMaximisesTrace(F, CalcRotationOfDeformation(F), &random);
  }
}

TEST(PolarDecomposition, InvertedMovesReflectionToSmallestSingularValue) {
  Random random(4);
  for (int k = 0; k < 1000; ++k) {
    Eigen::Matrix3d F = random.Matrix3();
    if (k % 2 == 1)
      F = random.Rotation() * Eigen::Vector3d(1.0, 0.8, -0.1).asDiagonal();  // pushed through
    if (F.determinant() > 0.0) F.col(1) *= -1.0;
    const Eigen::Vector3d sigma = Eigen::JacobiSVD<Eigen::Matrix3d>(F).singularValues();
    if (sigma[2] < 1e-6 * sigma[0] || sigma[1] - sigma[2] < 1e-6 * sigma[0]) continue;
    const Eigen::Matrix3d R = CalcRotationOfDeformation(F);
    const PolarChecks checks = CheckRotation(F, R);
    EXPECT_LE(checks.orthonormality, kRotationAccuracy);
    EXPECT_LE(checks.det_error, kRotationAccuracy);  // a rotation, not a reflection
    EXPECT_LE(checks.asymmetry, kSymmetryRoundOff * 2.0 * sigma[0] / (sigma[1] + sigma[2]));
    // Exactly one negative eigenvalue, −σ_min: the inversion is taken by the smallest stretch.
    EXPECT_LT(checks.eigenvalues[0], 0.0);
    EXPECT_GT(checks.eigenvalues[1], 0.0);
    EXPECT_NEAR(checks.eigenvalues[0], -sigma[2], kEigenvalueAccuracy * sigma[0]);
    EXPECT_NEAR(checks.eigenvalues[1], sigma[1], kEigenvalueAccuracy * sigma[0]);
    EXPECT_NEAR(checks.eigenvalues[2], sigma[0], kEigenvalueAccuracy * sigma[0]);
    if (k < 20) ExpectMaximisesTrace(F, R, &random);
  }
}

TEST(PolarDecomposition, FlatAndNearlyFlatGiveFiniteRotations) {
  Random random(9);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Matrix3d U = random.Rotation();
    const Eigen::Matrix3d V = random.Rotation();
    // Sweep the smallest singular value through zero (flat) to both orientations, across the
    // Newton/SVD switch (relative det 1e-3) and down to round-off.
    for (double sigma3 :
         {0.5, 1e-2, 2e-3, 1e-3, 5e-4, 1e-6, 1e-12, 0.0, -1e-12, -1e-6, -1e-2, -0.5}) {
      const Eigen::Matrix3d F = U * Eigen::Vector3d(2.0, 0.7, sigma3).asDiagonal() * V.transpose();
      const Eigen::Matrix3d R = CalcRotationOfDeformation(F);
      ASSERT_TRUE(R.allFinite()) << "sigma3 = " << sigma3;
      const PolarChecks checks = CheckRotation(F, R);
      EXPECT_LE(checks.orthonormality, kRotationAccuracy);
      EXPECT_LE(checks.det_error, kRotationAccuracy);
      EXPECT_LE(checks.asymmetry, kSymmetryRoundOff * 2.0 * 2.0 / 0.7);
      // tr(RᵀF) reaches its maximum over SO(3), σ₁ + σ₂ + σ₃ (signed smallest).
      EXPECT_NEAR((R.transpose() * F).trace(), 2.0 + 0.7 + sigma3, 1e-11) << "sigma3 = " << sigma3;
      // The rotation is continuous through flat: it is U Vᵀ whatever the sign of σ₃.
      EXPECT_LE((R - U * V.transpose()).norm(), 1e-9) << "sigma3 = " << sigma3;
    }
  }
  // Rank 1 and zero: still a rotation.
  const Eigen::Matrix3d rank_one =
      Eigen::Vector3d(1, 2, 3) * Eigen::Vector3d(0.5, -1, 0.2).transpose();
  for (const Eigen::Matrix3d& F : {rank_one, Eigen::Matrix3d(Eigen::Matrix3d::Zero())}) {
    const Eigen::Matrix3d R = CalcRotationOfDeformation(F);
    ASSERT_TRUE(R.allFinite());
    EXPECT_LE((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), kRotationAccuracy);
    EXPECT_NEAR(R.determinant(), 1.0, kRotationAccuracy);
  }
}

// ---------------------------------------------------------------------------------------------
// 2. CalcRotationsOfDeformation against the scalar function.

// The batch repeats the scalar function's operations except for the order of two sums (‖F‖²,
// ‖ΔX‖²) and a γ within 2 ulp of cbrt's, so it agrees to round-off (measured ≤ 1e-15), unless a
// convergence test flips at its threshold: one step more or less then changes R by at most the
// ≤ 5e-13 the iteration leaves in it.
constexpr double kBatchAgreement = 1e-12;
// Orthonormality and det of R entry by entry (max |·|); Frobenius norms above are ≤ 3 times it.
constexpr double kBatchRotationAccuracy = 1e-12;
// Against Eigen's SVD polar factor U Vᵀ, for stretches in [0.5, 2] (conditioning 2σ₁/(σ₂ + σ₃)
// ≤ 4; kPolarAgreement above times it is 2e-11).
constexpr double kBatchPolarAgreement = 1e-10;

double MaxAbsDifference(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return (A - B).cwiseAbs().maxCoeff();
}

// F = Q Vᵀ diag(s) V with s log-uniform in [0.5, 2]: det X is far from 1, so the first
// iterations take the scaling γ = ∛(1/det X).
Eigen::Matrix3d RandomStretchedRotation(Random* random) {
  const Eigen::Matrix3d V = random->Rotation();
  const Eigen::Vector3d s(std::exp2(random->Uniform()), std::exp2(random->Uniform()),
                          std::exp2(random->Uniform()));
  return random->Rotation() * V.transpose() * s.asDiagonal() * V;
}

// Checks R[i] against CalcRotationOfDeformation(F[i]) and that it is a rotation; returns the
// largest entry difference.
double ExpectMatchesScalar(const std::vector<Eigen::Matrix3d>& F,
                           const std::vector<Eigen::Matrix3d>& R) {
  double worst = 0.0;
  for (size_t i = 0; i < F.size(); ++i) {
    const double difference = MaxAbsDifference(R[i], CalcRotationOfDeformation(F[i]));
    EXPECT_LE(difference, kBatchAgreement) << "element " << i << ", F =\n" << F[i];
    EXPECT_LE(MaxAbsDifference(R[i].transpose() * R[i], Eigen::Matrix3d::Identity()),
              kBatchRotationAccuracy)
        << "element " << i;
    EXPECT_NEAR(R[i].determinant(), 1.0, kBatchRotationAccuracy) << "element " << i;
    worst = std::max(worst, difference);
  }
  return worst;
}

std::vector<Eigen::Matrix3d> CalcBatched(const std::vector<Eigen::Matrix3d>& F) {
  std::vector<Eigen::Matrix3d> R(F.size());
  CalcRotationsOfDeformation(F.data(), static_cast<int>(F.size()), R.data());
  return R;
}

TEST(BatchedPolarDecomposition, StretchedRotationsMatchScalarAndSvdPolarFactor) {
  Random random(21);
  std::vector<Eigen::Matrix3d> F(4000);
  int scaled = 0;  // elements whose first iteration needs γ
  for (Eigen::Matrix3d& f : F) {
    f = RandomStretchedRotation(&random);
    const double relative_det = f.determinant() / std::pow(f.norm() / std::sqrt(3.0), 3);
    if (std::abs(relative_det - 1.0) >= 1e-3) ++scaled;
  }
  EXPECT_GE(scaled, 3900);
  const std::vector<Eigen::Matrix3d> R = CalcBatched(F);
  const double worst = ExpectMatchesScalar(F, R);
  double worst_polar = 0.0;
  for (size_t i = 0; i < F.size(); ++i) {
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(F[i], Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d polar = svd.matrixU() * svd.matrixV().transpose();  // det F > 0
    const double difference = MaxAbsDifference(R[i], polar);
    EXPECT_LE(difference, kBatchPolarAgreement) << "element " << i;
    worst_polar = std::max(worst_polar, difference);
  }
  std::printf(
      "%zu stretched (%d scaled): max |batched - scalar| = %.2e, |batched - U V^T| = %.2e\n",
      F.size(), scaled, worst, worst_polar);
}

// One of each element the fast path refuses or finds hard, and fast ones beside them.
std::vector<Eigen::Matrix3d> MakeMixedElements(Random* random) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Eigen::Matrix3d U = random->Rotation(), V = random->Rotation();
  std::vector<Eigen::Matrix3d> F = {
      U * Eigen::Vector3d(1.0, 0.8, -0.1).asDiagonal() * V.transpose(),      // inverted
      U * Eigen::Vector3d(2.0, 0.7, 0.0).asDiagonal() * V.transpose(),       // flat (rank 2)
      Eigen::Vector3d(1, 2, 3) * Eigen::Vector3d(0.5, -1, 0.2).transpose(),  // rank 1
      Eigen::Matrix3d::Zero(),
      // Nearly flat, det X = 1.5e-3 just above the fast path's threshold: the most iterations.
      U * Eigen::Vector3d(2.0, 0.7, 2e-3).asDiagonal() * V.transpose(),
      1e200 * U,  // ‖F‖² overflows
      Eigen::Matrix3d::Identity(),
      U,                                                             // a rotation
      U * (Eigen::Matrix3d::Identity() + 1e-9 * random->Matrix3()),  // near a rotation
  };
  Eigen::Matrix3d with_nan = RandomStretchedRotation(random);
  with_nan(1, 2) = nan;
  F.push_back(with_nan);
  F.push_back(Eigen::Matrix3d::Constant(std::numeric_limits<double>::infinity()));
  for (int k = 0; k < 5; ++k) F.push_back(RandomStretchedRotation(random));
  return F;
}

// Fallback lanes take the scalar path without disturbing the fast lanes of their block: every
// element's result is bit for bit the one it gets alone, whatever its neighbours.
TEST(BatchedPolarDecomposition, FallbackLanesDoNotDisturbTheirNeighbours) {
  Random random(22);
  std::mt19937 engine(23);
  double worst = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<Eigen::Matrix3d> F = MakeMixedElements(&random);
    const std::vector<Eigen::Matrix3d> more = MakeMixedElements(&random);
    F.insert(F.end(), more.begin(), more.end());
    std::shuffle(F.begin(), F.end(), engine);  // other neighbours in every trial
    const std::vector<Eigen::Matrix3d> R = CalcBatched(F);
    worst = std::max(worst, ExpectMatchesScalar(F, R));
    for (size_t i = 0; i < F.size(); ++i) {
      ASSERT_TRUE(R[i].allFinite()) << "element " << i << ", F =\n" << F[i];
      EXPECT_TRUE(R[i] == CalcBatched({F[i]})[0]) << "element " << i << ", F =\n" << F[i];
    }
  }
  std::printf("mixed blocks: max |batched - scalar| = %.2e\n", worst);
}

// Every count around the block size: results for the first `count` elements, nothing written
// past them; and the same results in place (R = F).
TEST(BatchedPolarDecomposition, AnyCountAndInPlace) {
  Random random(24);
  const Eigen::Matrix3d sentinel = Eigen::Matrix3d::Constant(7.0);
  double worst = 0.0;
  for (int count : {0, 1, kPolarBatchLanes - 1, kPolarBatchLanes, kPolarBatchLanes + 1, 1000}) {
    std::vector<Eigen::Matrix3d> F(count);
    for (int i = 0; i < count; ++i) {
      F[i] = RandomStretchedRotation(&random);
      if (i % 7 == 3) F[i].col(0) *= -1.0;  // inverted: a fallback lane here and there
    }
    std::vector<Eigen::Matrix3d> R(count + kPolarBatchLanes, sentinel);
    CalcRotationsOfDeformation(F.data(), count, R.data());
    for (int i = count; i < count + kPolarBatchLanes; ++i) EXPECT_TRUE(R[i] == sentinel);
    R.resize(count);
    worst = std::max(worst, ExpectMatchesScalar(F, R));
    std::vector<Eigen::Matrix3d> in_place = F;
    CalcRotationsOfDeformation(in_place.data(), count, in_place.data());
    for (int i = 0; i < count; ++i) EXPECT_TRUE(in_place[i] == R[i]) << "count " << count;
  }
  std::printf("counts: max |batched - scalar| = %.2e\n", worst);
}

}  // namespace
}  // namespace hapsim::fem
