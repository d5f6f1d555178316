// The visual frame's friction solve (contact/frame_friction_solver.h: working set, sweeps by
// columns, Newton steps) against an independent value: the dense blocked projected Gauss–Seidel
// (FrictionMethod::kDenseGaussSeidel, the solver it replaces: W formed and swept row by row, no
// working set, no Newton) run to a tight tolerance, on random well-posed friction problems
// (haptic_test_problems.h: random contact normals and points, a random SPD body matrix A_u, so
// W_body = J_u A_u⁻¹ J_uᵀ is SPD, and a tool whose coupling makes W non-symmetric; μ constant
// or per contact, zeros included). Both stop on CalcFrictionResidual ≤ 1e-13, whose zero is
// Coulomb's law; where the solution is unique they must agree to 1e-8 of the largest impulse
// (the figure: the residual bounds the error by the residual times a condition number,
// ~1e3 here). The problems are checked to hold separated, sticking and sliding contacts, and
// the solver's returned iterate to be admissible when cut off.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <random>
#include <string>

#include "contact/contact_solver.h"
#include "contact/frame_friction_solver.h"
#include "tests/contact/haptic_test_problems.h"

namespace hapsim::contact {
namespace {

constexpr double kTolerance = 1e-13;     // both solvers' residual
constexpr double kAgreement = 1e-8;      // |λ − λ_dense|∞ / |λ_dense|∞
constexpr int kDenseSweeps = 2'000'000;  // the dense solver converges linearly, slowly
constexpr double kDt_frame_s = 0.03;     // the visual step (the rows' own Δt is the haptic one)

struct Solved {
  Eigen::VectorXd lambda;
  ContactSolveReport report;
};

Solved Solve(const DenseProblem& dense, const Eigen::VectorXd& mu, FrictionMethod method,
             int max_sweeps = kDenseSweeps) {
  ContactSolveOptions options{ContactLaw::kFriction};
  options.friction_method = method;
  options.max_iterations = max_sweeps;
  options.tolerance = kTolerance;
  Solved solved;
  solved.report =
      SolveContactImpulses(dense.W, dense.rhs, kDt_frame_s, 3, options, &solved.lambda, &mu);
  return solved;
}

struct Case {
  int contacts;
  double press;
  double mu;                // < 0: per contact, uniform in [0, 1) with every fourth 0
  double body_scale = 1.0;  // small: a stiff body, W close to the rank-6 tool part (slow sweeps)
};

Eigen::VectorXd MakeMu(const Case& k, unsigned seed) {
  if (k.mu >= 0.0) return Eigen::VectorXd::Constant(k.contacts, k.mu);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Eigen::VectorXd mu(k.contacts);
  for (int i = 0; i < k.contacts; ++i) mu[i] = i % 4 == 3 ? 0.0 : unit(rng);
  return mu;
}

TEST(FrameFrictionSolver, MatchesDenseGaussSeidelOnRandomRows) {
  const Case cases[] = {{4, 0.1, 0.5},        {12, 0.0, 0.3},       {12, 0.3, -1.0},
                        {30, 0.1, 0.5},       {30, 0.5, -1.0},      {60, 0.2, 0.4},
                        {30, 0.3, 0.5, 0.02}, {60, 0.2, -1.0, 0.05}};
  int separated = 0, sticking = 0, sliding = 0;
  for (const Case& k : cases) {
    for (unsigned seed = 1; seed <= 4; ++seed) {
      const std::string at = std::to_string(k.contacts) + " contacts, press " +
                             std::to_string(k.press) + ", body " + std::to_string(k.body_scale) +
                             ", seed " + std::to_string(seed);
      const LcpProblem p = MakeLcpProblem(k.contacts, 7000 + 100 * k.contacts + seed, k.press,
                                          k.body_scale, 3, std::max(k.mu, 0.0));
      const DenseProblem dense = AssembleDense(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m);
      const Eigen::VectorXd mu = MakeMu(k, seed);
      const Solved reference = Solve(dense, mu, FrictionMethod::kDenseGaussSeidel);
      ASSERT_TRUE(reference.report.converged) << at << ": dense " << reference.report.residual;
      const Solved solved = Solve(dense, mu, FrictionMethod::kWorkingSet);
      EXPECT_TRUE(solved.report.converged) << at << ": residual " << solved.report.residual;
      EXPECT_LE(CalcFrictionResidual(dense.W, dense.rhs, kDt_frame_s, 0.0, &mu, solved.lambda),
                10 * kTolerance)
          << at;
      const double scale = reference.lambda.lpNorm<Eigen::Infinity>();
      ASSERT_GT(scale, 0.0) << at;
      EXPECT_LE((solved.lambda - reference.lambda).lpNorm<Eigen::Infinity>(), kAgreement * scale)
          << at << ": " << reference.report.iterations << " dense sweeps, "
          << solved.report.iterations << " sweeps and " << solved.report.newton_steps
          << " Newton steps";
      for (int i = 0; i < k.contacts; ++i) {
        const double normal = reference.lambda[3 * i];
        const double tangential = reference.lambda.segment<2>(3 * i + 1).norm();
        if (!(normal > 0.0))
          ++separated;
        else if (mu[i] > 0.0 && tangential >= (1.0 - 1e-9) * mu[i] * normal)
          ++sliding;
        else
          ++sticking;
      }
    }
  }
  // The comparison covers every state of the law, in numbers.
  EXPECT_GE(separated, 20);
  EXPECT_GE(sticking, 20);
  EXPECT_GE(sliding, 20);
}

// Cut off after a few sweeps (before any Newton step can converge), the iterate is admissible:
// λ_n ≥ 0 and |λ_t| ≤ μλ_n, never pulling.
TEST(FrameFrictionSolver, CutOffIterateIsAdmissible) {
  const LcpProblem p = MakeLcpProblem(30, 43, 0.3, 1.0, 3, 0.5);
  const DenseProblem dense = AssembleDense(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m);
  const Eigen::VectorXd mu = Eigen::VectorXd::Constant(30, 0.5);
  for (int sweeps : {1, 2, 5, 9}) {
    const Solved solved = Solve(dense, mu, FrictionMethod::kWorkingSet, sweeps);
    EXPECT_LE(solved.report.iterations, sweeps);
    for (int i = 0; i < 30; ++i) {
      EXPECT_GE(solved.lambda[3 * i], 0.0);
      EXPECT_LE(solved.lambda.segment<2>(3 * i + 1).norm(),
                mu[i] * solved.lambda[3 * i] * (1.0 + 1e-12));
    }
  }
}

// A start far from the solution (5 N on every row, the tangents then projected onto the rim)
// ends at the same solution as a cold start: the start only changes the work.
TEST(FrameFrictionSolver, WarmStartReachesTheSameSolution) {
  const LcpProblem p = MakeLcpProblem(30, 45, 0.2, 1.0, 3, 0.5);
  const DenseProblem dense = AssembleDense(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m);
  const Eigen::VectorXd mu = Eigen::VectorXd::Constant(30, 0.5);
  const Solved cold = Solve(dense, mu, FrictionMethod::kWorkingSet);
  ContactSolveOptions options{ContactLaw::kFriction};
  options.tolerance = kTolerance;
  Eigen::VectorXd warm = Eigen::VectorXd::Constant(90, 5.0);
  const ContactSolveReport report =
      SolveContactImpulses(dense.W, dense.rhs, kDt_frame_s, 3, options, &warm, &mu);
  EXPECT_TRUE(report.converged) << report.residual;
  EXPECT_LE((warm - cold.lambda).lpNorm<Eigen::Infinity>(),
            kAgreement * cold.lambda.lpNorm<Eigen::Infinity>());
}

TEST(FrameFrictionSolver, RejectsInconsistentSizes) {
  Eigen::VectorXd lambda;
  const ContactSolveOptions options{ContactLaw::kFriction};
  EXPECT_THROW(SolveFrictionOnWorkingSet(Eigen::MatrixXd::Identity(6, 6), Eigen::VectorXd::Ones(6),
                                         kDt_frame_s, Eigen::VectorXd::Ones(3), options, &lambda),
               std::invalid_argument);
  EXPECT_THROW(SolveFrictionOnWorkingSet(Eigen::MatrixXd::Identity(4, 4), Eigen::VectorXd::Ones(4),
                                         kDt_frame_s, Eigen::VectorXd::Ones(1), options, &lambda),
               std::invalid_argument);
}

}  // namespace
}  // namespace hapsim::contact
