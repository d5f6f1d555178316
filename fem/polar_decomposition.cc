#include "fem/polar_decomposition.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

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

// ---------------------------------------------------------------------------------------------
// Batched form: the iteration above on kLanes elements side by side. One element's iteration is
// a chain of dependent steps (cofactor → det → division → next iterate → convergence test), so
// run alone it waits on latencies; independent lanes fill the pipeline and the vector units.

namespace {

constexpr int kLanes = kPolarBatchLanes;
constexpr int kMaxCubeRootSteps = 12;
constexpr double kCubeRootFinalResidual = 1e-5;

// The functions below are inlined by force: CalcRotationsByLanes has clones for several targets
// (below), and GCC does not inline an ordinary function into them otherwise.
//
// Structure of arrays: entry k of lane l's 3×3 matrix (column-major, as Eigen stores a
// Matrix3d) is at [k][l]. Each function below loops over the lanes with a fixed trip count and a
// branch-free body, which GCC vectorises (check: -fopt-info-vec). The arithmetic repeats
// CalcRotationOfDeformation's, so a lane's result is the scalar one up to the order of two sums
// and the last bits of γ.
struct alignas(64) LaneBlock {
  double x[9][kLanes];  // the iterate X
  double det[kLanes];
  double gamma[kLanes];          // Higham's scaling; 1 near det X = 1 and in inactive lanes
  double needs_scaling[kLanes];  // 1.0 where γ ≠ 1 (active and det X outside the band)
  double active[kLanes];         // 1.0 while iterating, 0.0 once converged or off the fast path
  double fast[kLanes];           // 1.0 on the fast path, 0.0 if the scalar function takes the lane
};

// Lanes past `count` hold the identity: converged at once, they cost no extra iteration.
[[gnu::always_inline]] inline void LoadLanes(const Eigen::Matrix3d* F, int count, LaneBlock* b) {
  const int full = count < kLanes ? count : kLanes;
  for (int l = 0; l < full; ++l) {
    for (int k = 0; k < 9; ++k) b->x[k][l] = F[l](k);
  }
  for (int l = full; l < kLanes; ++l) {
    for (int k = 0; k < 9; ++k) b->x[k][l] = k % 4 == 0 ? 1.0 : 0.0;
  }
}

// X = F / (‖F‖_F/√3), then the fast-path test of the scalar function: scale finite and positive,
// det X (Eigen's 3×3 formula) at least kMinRelativeDeterminant. A lane that fails (NaN
// included) is left to the scalar function and holds the identity meanwhile, finite and inactive.
[[gnu::always_inline]] inline void NormaliseLanes(LaneBlock* b) {
  for (int l = 0; l < kLanes; ++l) {
    double sum_sq = 0.0;
    for (int k = 0; k < 9; ++k) sum_sq += b->x[k][l] * b->x[k][l];
    const double scale = std::sqrt(sum_sq) / std::sqrt(3.0);
    const double inverse = 1.0 / scale;
    double x[9];
    for (int k = 0; k < 9; ++k) x[k] = b->x[k][l] * inverse;
    // x[r + 3c] = X(r, c).
    // Eigen's 3×3 determinant, X(0,0)(X(1,1)X(2,2) − X(1,2)X(2,1)) − X(0,1)(..) + X(0,2)(..),
    // term for term, so the fast-path test decides as the scalar function's does.
    const double det = x[0] * (x[4] * x[8] - x[7] * x[5]) - x[3] * (x[1] * x[8] - x[7] * x[2]) +
                       x[6] * (x[1] * x[5] - x[4] * x[2]);
    const bool fast = (scale > 0.0) & (scale <= std::numeric_limits<double>::max()) &
                      (det >= kMinRelativeDeterminant);  // each false for NaN
    for (int k = 0; k < 9; ++k) b->x[k][l] = fast ? x[k] : (k % 4 == 0 ? 1.0 : 0.0);
    b->fast[l] = fast ? 1.0 : 0.0;
    b->active[l] = b->fast[l];
  }
}

[[gnu::always_inline]] inline bool AnyLane(const double (&flag)[kLanes]) {
  bool any = false;
  for (int l = 0; l < kLanes; ++l) any |= flag[l] != 0.0;
  return any;
}

// det X = x_0 · (x_1 × x_2), x_j the columns of X, as the scalar function computes it, and γ = 1.
// Returns whether an active lane is outside the band where γ = 1 is kept.
[[gnu::always_inline]] inline bool CalcDeterminantLanes(LaneBlock* b) {
  for (int l = 0; l < kLanes; ++l) {
    double x[9];
    for (int k = 0; k < 9; ++k) x[k] = b->x[k][l];
    const double det = x[0] * (x[4] * x[8] - x[5] * x[7]) + x[1] * (x[5] * x[6] - x[3] * x[8]) +
                       x[2] * (x[3] * x[7] - x[4] * x[6]);
    b->det[l] = det;
    b->gamma[l] = 1.0;
    b->needs_scaling[l] = std::abs(det - 1.0) < kSkipScalingDeterminantBand ? 0.0 : b->active[l];
  }
  return AnyLane(b->needs_scaling);
}

// γ = (det X)^(−1/3) (Higham 1986) in the lanes CalcDeterminantLanes marked, γ = 1 elsewhere.
// libm's cbrt does not vectorise; instead Halley's iteration for the cube root of 1/d,
// t ← t (d t³ + 2) / (2 d t³ + 1), from t = 1: far from the root a step doubles or halves t,
// near it the relative error e ≈ (d t³ − 1)/3 is cubed. A step taken from |d t³ − 1| ≤ 1e-5
// thus ends at round-off (within 2 ulp of cbrt(1/d)); it is the lane's last, and t is frozen
// after it as X is in StepLanes, so that γ does not depend on the other lanes. Steps: 3 for d in
// [0.5, 2], 7 in [1e-3, 6e3], which holds det X for the iterates of a normalised X with
// det X ≥ 1e-3 (measured up to 2.9e3), 10 in [2⁻²¹, 2²¹]. A lane stopped short by
// kMaxCubeRootSteps, or NaN, has a rougher or NaN γ: the first slows the Newton iteration, not
// its limit; the second makes the lane fail to converge and go to the scalar function.
[[gnu::always_inline]] inline void CalcScalingLanes(LaneBlock* b) {
  double stepping[kLanes];
  for (int l = 0; l < kLanes; ++l) stepping[l] = b->needs_scaling[l];  // others keep γ = 1
  for (int step = 0; step < kMaxCubeRootSteps && AnyLane(stepping); ++step) {
    // Small enough for GCC to unroll completely, after which the divisions stay scalar.
#pragma GCC unroll 1
    for (int l = 0; l < kLanes; ++l) {
      const double t = b->gamma[l];
      const double p = b->det[l] * (t * t * t);
      const double ratio = (p + 2.0) / (2.0 * p + 1.0);
      // ratio · 1 + 0 or ratio · 0 + 1, exact for finite ratio: a multiplying 0/1 flag rather
      // than a select, which GCC would turn into a branch (see StepLanes).
      b->gamma[l] = t * (ratio * stepping[l] + (1.0 - stepping[l]));
      stepping[l] = std::abs(p - 1.0) > kCubeRootFinalResidual ? stepping[l] : 0.0;
    }
  }
}

// One scaled Newton step X ← (γX + X⁻ᵀ/γ)/2 = (γ/2) X + (1/(2γ det X)) cof(X), the cofactor
// columns x_1 × x_2, x_2 × x_0, x_0 × x_1 as CalcCofactor. A lane whose step is below the
// tolerance keeps that step's result, as the scalar function returns it, and is frozen from then
// on: inactive lanes have a = 1, c = 0 (finite X, cof and γ = 1), so X + 0 = X exactly. The 0/1
// flag multiplies rather than selects: with a select GCC moves the division under a branch and
// the loop no longer vectorises. Returns whether a lane is still active.
[[gnu::always_inline]] inline bool StepLanes(LaneBlock* b) {
  for (int l = 0; l < kLanes; ++l) {
    const double active = b->active[l];
    const double a = 0.5 * b->gamma[l] * active + (1.0 - active);
    const double c = 0.5 / (b->gamma[l] * b->det[l]) * active;
    double x[9], cofactor[9], change_sq[9];
    for (int k = 0; k < 9; ++k) x[k] = b->x[k][l];
    for (int j = 0; j < 3; ++j) {
      const int p = 3 * ((j + 1) % 3), q = 3 * ((j + 2) % 3);
      cofactor[3 * j + 0] = x[p + 1] * x[q + 2] - x[p + 2] * x[q + 1];
      cofactor[3 * j + 1] = x[p + 2] * x[q + 0] - x[p + 0] * x[q + 2];
      cofactor[3 * j + 2] = x[p + 0] * x[q + 1] - x[p + 1] * x[q + 0];
    }
    for (int k = 0; k < 9; ++k) {
      const double next = a * x[k] + c * cofactor[k];
      change_sq[k] = (next - x[k]) * (next - x[k]);
      b->x[k][l] = next;
    }
    // A tree, not a chain of nine dependent additions.
    const double change_sq_sum = ((change_sq[0] + change_sq[1]) + (change_sq[2] + change_sq[3])) +
                                 ((change_sq[4] + change_sq[5]) + (change_sq[6] + change_sq[7])) +
                                 change_sq[8];
    // A NaN step stays active: the lane then ends unconverged and goes to the scalar function.
    b->active[l] = change_sq_sum < kNewtonStepTolerance * kNewtonStepTolerance ? 0.0 : active;
  }
  return AnyLane(b->active);
}

// Lanes off the fast path, or still active after the last iteration (not converged), take the
// scalar function, which holds the SVD fallback.
[[gnu::always_inline]] inline void StoreLanes(const LaneBlock& b, const Eigen::Matrix3d* F,
                                              int count, Eigen::Matrix3d* R) {
  for (int l = 0; l < count; ++l) {
    if (b.fast[l] == 0.0 || b.active[l] != 0.0) {
      R[l] = CalcRotationOfDeformation(F[l]);
    } else {
      for (int k = 0; k < 9; ++k) R[l](k) = b.x[k][l];
    }
  }
}

// On x86-64 with glibc, an AVX2 clone besides the baseline SSE2 one, picked once at load time
// (GCC/Clang function multiversioning, through an ifunc): four lanes per instruction instead of
// two. Target "avx2" only, without FMA, so the two clones round alike and the result does not
// depend on the machine. The build itself stays baseline x86-64. The clones are of this internal
// function, not of the public one: Clang 14 mishandles clones of a function declared before
// without the attribute (as in the header).
// Not under ThreadSanitizer: ld.so calls the ifunc's resolver while it relocates the program,
// before TSan's runtime exists, and GCC 12 and Clang 14 both instrument the resolver
// (__tsan_func_entry), so every program linking this file died with SIGSEGV before main (issue
// 25; google/sanitizers#342). The TSan build takes the baseline loop alone.
#if defined(__x86_64__) && defined(__GLIBC__) && (defined(__GNUC__) || defined(__clang__))
#if defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define HAPSIM_THREAD_SANITIZER 1
#endif
#endif
#if !defined(__SANITIZE_THREAD__) && !defined(HAPSIM_THREAD_SANITIZER)
__attribute__((target_clones("avx2", "default")))
#endif
#endif
void CalcRotationsByLanes(const Eigen::Matrix3d* F, int count, Eigen::Matrix3d* R) {
  for (int start = 0; start < count; start += kLanes) {
    const int lanes = std::min(kLanes, count - start);
    LaneBlock block;
    LoadLanes(F + start, lanes, &block);
    NormaliseLanes(&block);
    bool any_active = AnyLane(block.active);
    for (int iteration = 0; iteration < kMaxNewtonIterations && any_active; ++iteration) {
      if (CalcDeterminantLanes(&block)) CalcScalingLanes(&block);
      any_active = StepLanes(&block);
    }
    StoreLanes(block, F + start, lanes, R + start);
  }
}

}  // namespace

void CalcRotationsOfDeformation(const Eigen::Matrix3d* F, int count, Eigen::Matrix3d* R) {
  CalcRotationsByLanes(F, count, R);
}

}  // namespace hapsim::fem
