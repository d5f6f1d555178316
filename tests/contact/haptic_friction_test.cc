// Coulomb friction in the haptic step's solve (contact/haptic_friction_solver.h) against
// independent values:
//  - Coulomb's law itself, checked on the densely assembled W and rhs: λ_n ≥ 0 ⟂ c_n ≥ 0,
//    |λ_t| ≤ μλ_n, c_t = 0 where the contact sticks, λ_t opposite c_t where it slides;
//  - SolveContactImpulses(kFriction) on that dense W (the visual frame's solver: W formed and
//    swept row by row), cold and while the tool's wrench changes step to step;
//  - the frictionless solve (HapticLcpSolver, exact active set) at μ = 0;
//  - no heap allocation after construction at 510 rows; admissible iterates (never pulling)
//    when cut off after one sweep, and the contacts released when the tool is pulled away.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "contact/contact_solver.h"
#include "contact/haptic_friction_solver.h"
#include "contact/haptic_lcp_solver.h"
#include "tests/allocation_counter.h"
#include "tests/contact/haptic_test_problems.h"

namespace hapsim::contact {
namespace {

constexpr int kManySweeps = 200000;

struct LawCount {
  int separated = 0, sticking = 0, sliding = 0;
};

// Coulomb's law on the dense problem, to `tolerance` of the size of the terms summed in c (for
// velocities) and of the largest λ (for impulses).
LawCount ExpectCoulomb(const DenseProblem& dense, const Eigen::VectorXd& mu, double dt_s,
                       const Eigen::VectorXd& lambda, double tolerance, const std::string& where) {
  const Eigen::VectorXd c = dt_s * dense.W * lambda - dense.rhs;
  const double c_scale =
      (dt_s * dense.W.cwiseAbs() * lambda.cwiseAbs()).maxCoeff() + dense.rhs.cwiseAbs().maxCoeff();
  const double lambda_scale = std::max(lambda.cwiseAbs().maxCoeff(), 1e-300);
  LawCount count;
  for (Eigen::Index i = 0; i < mu.size(); ++i) {
    const double l_n = lambda[3 * i], c_n = c[3 * i];
    const Eigen::Vector2d l_t = lambda.segment<2>(3 * i + 1), c_t = c.segment<2>(3 * i + 1);
    const std::string at = where + " contact " + std::to_string(i);
    EXPECT_GE(l_n, 0.0) << at;
    EXPECT_GE(c_n, -tolerance * c_scale) << at;
    EXPECT_LE(l_t.norm(), mu[i] * l_n * (1.0 + 1e-12) + 1e-300) << at;
    if (l_n <= 0.0) {
      ++count.separated;
      continue;
    }
    EXPECT_LE(std::abs(c_n), tolerance * c_scale) << at;
    if (l_t.norm() < mu[i] * l_n * (1.0 - 1e-6)) {
      ++count.sticking;
      EXPECT_LE(c_t.norm(), tolerance * c_scale) << at << " sticks";
    } else if (mu[i] > 0.0) {
      ++count.sliding;
      // λ_t = −μλ_n c_t/|c_t| (or the contact is at the rim with c_t = 0).
      if (c_t.norm() > tolerance * c_scale) {
        EXPECT_LE((l_t + mu[i] * l_n * c_t.normalized()).norm(), 1e3 * tolerance * lambda_scale)
            << at << " slides";
      }
    }
  }
  return count;
}

Eigen::VectorXd SolveDense(const DenseProblem& dense, const Eigen::VectorXd& mu, double dt_s) {
  ContactSolveOptions options{ContactLaw::kFriction};
  options.max_iterations = kManySweeps;
  options.tolerance = 1e-13;
  Eigen::VectorXd lambda;
  const ContactSolveReport report =
      SolveContactImpulses(dense.W, dense.rhs, dt_s, 3, options, &lambda, &mu);
  EXPECT_TRUE(report.converged) << "dense reference residual " << report.residual;
  return lambda;
}

// One tangential step (contact_solver.h): a projected step of 1/(Δt ω) against c_t; nothing
// when the disc or ω is zero (no division by zero, no NaN).
TEST(StepTangentialImpulse, StepsProjectsAndDegeneratesToZero) {
  Eigen::Matrix2d W_tt;
  W_tt << 2.0, 0.5, 0.5, 3.0;  // ω = 3.5
  const Eigen::Vector2d lambda_t(0.1, 0.0), c_t(-0.0035, 0.0035);
  const Eigen::Vector2d free = lambda_t - c_t / (kDt_s * 3.5);  // (1.1, −1.0)
  EXPECT_LT((StepTangentialImpulse(lambda_t, c_t, W_tt, kDt_s, 10.0) - free).norm(), 1e-12);
  EXPECT_LT(
      (StepTangentialImpulse(lambda_t, c_t, W_tt, kDt_s, 0.5) - 0.5 * free.normalized()).norm(),
      1e-12);
  EXPECT_EQ(StepTangentialImpulse(lambda_t, c_t, W_tt, kDt_s, 0.0), Eigen::Vector2d::Zero());
  EXPECT_EQ(StepTangentialImpulse(lambda_t, c_t, Eigen::Matrix2d::Zero(), kDt_s, 1.0),
            Eigen::Vector2d::Zero());
}

TEST(MakeFrictionContactRows, KeepsTheLayoutAndChecksMu) {
  const LcpProblem p = MakeLcpProblem(4, 5, 0.5, 1.0, 3, 0.4);
  EXPECT_EQ(p.rows.rows_per_contact, 3);
  EXPECT_EQ(p.rows.num_rows(), 12);
  EXPECT_EQ(p.rows.friction_coefficient, Eigen::VectorXd::Constant(4, 0.4));
  EXPECT_TRUE(HasConsistentShape(p.rows));
  const Eigen::MatrixXd W = p.rows.W_body;
  EXPECT_THROW(MakeFrictionContactRows(p.J, W, p.rows.body_rhs, Eigen::VectorXd::Constant(3, 0.4)),
               std::invalid_argument);
  EXPECT_THROW(MakeFrictionContactRows(p.J, W, p.rows.body_rhs, Eigen::VectorXd::Constant(4, -0.1)),
               std::invalid_argument);
  const LcpProblem normal = MakeLcpProblem(4, 5);
  EXPECT_THROW(MakeFrictionContactRows(normal.J, normal.rows.W_body, normal.rows.body_rhs,
                                       Eigen::VectorXd::Constant(4, 0.4)),
               std::invalid_argument);
}

// Cold: many sweeps, so the solve is converged; it must satisfy Coulomb's law and agree with the
// dense reference. Over the cases every regime occurs: separated, sticking and sliding contacts.
TEST(HapticFrictionSolver, SatisfiesCoulombAndMatchesTheDenseReference) {
  struct Case {
    int contacts;
    double press, mu;
  };
  const Case cases[] = {{2, 0.3, 0.5},  {8, 0.0, 0.3},  {8, 0.3, 1.0},
                        {20, 0.1, 0.5}, {50, 0.2, 0.2}, {50, 0.5, 2.0}};
  LawCount total;
  for (const Case& k : cases) {
    for (unsigned seed = 1; seed <= 2; ++seed) {
      const std::string where = "m " + std::to_string(k.contacts) + " mu " + std::to_string(k.mu) +
                                " seed " + std::to_string(seed);
      const LcpProblem p =
          MakeLcpProblem(k.contacts, 1000 * k.contacts + seed, k.press, 1.0, 3, k.mu);
      HapticFrictionSolver solver(3 * 50, kManySweeps);
      Eigen::Vector3d F_c, T_c;
      ASSERT_TRUE(solver.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_c, &T_c)) << where;
      EXPECT_LT(solver.last_iterations(), kManySweeps) << where << ": not converged";
      EXPECT_LT(solver.last_residual(), 1e-9) << where;
      const Eigen::VectorXd lambda = solver.last_impulses();
      const DenseProblem dense = AssembleDense(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m);
      const LawCount count =
          ExpectCoulomb(dense, p.rows.friction_coefficient, kDt_s, lambda, 1e-9, where);
      total.separated += count.separated;
      total.sticking += count.sticking;
      total.sliding += count.sliding;
      const Eigen::VectorXd reference = SolveDense(dense, p.rows.friction_coefficient, kDt_s);
      EXPECT_LE((lambda - reference).norm(), 1e-8 * std::max(reference.norm(), 1e-300)) << where;
      EXPECT_LE((F_c - p.rows.J_v.transpose() * reference).norm(),
                1e-8 * reference.cwiseAbs().sum())
          << where;
      EXPECT_EQ(solver.last_num_active(), count.sticking + count.sliding) << where;
    }
  }
  std::printf("contacts over the cases: %d separated, %d sticking, %d sliding\n", total.separated,
              total.sticking, total.sliding);
  EXPECT_GT(total.separated, 0);
  EXPECT_GT(total.sticking, 0);
  EXPECT_GT(total.sliding, 0);
}

// μ = 0: the normal rows of the friction solve are the frictionless LCP on the normal rows
// alone (the tangential impulses are zero), which HapticLcpSolver solves exactly.
TEST(HapticFrictionSolver, WithoutFrictionIsTheFrictionlessLcp) {
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const LcpProblem p = MakeLcpProblem(12, 70 + seed, 0.2, 1.0, 3, 0.0);
    HapticFrictionSolver friction(36, kManySweeps);
    Eigen::Vector3d F_friction, T_friction;
    ASSERT_TRUE(friction.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_friction, &T_friction));
    // The normal rows alone: every third row of each part.
    ContactRows normal;
    const int m = 12;
    normal.J_v.resize(m, 3);
    normal.J_w.resize(m, 3);
    normal.W_body.resize(m, m);
    normal.body_rhs.resize(m);
    for (int i = 0; i < m; ++i) {
      normal.J_v.row(i) = p.rows.J_v.row(3 * i);
      normal.J_w.row(i) = p.rows.J_w.row(3 * i);
      normal.body_rhs[i] = p.rows.body_rhs[3 * i];
      for (int j = 0; j < m; ++j) normal.W_body(i, j) = p.rows.W_body(3 * i, 3 * j);
    }
    HapticLcpSolver lcp(m);
    Eigen::Vector3d F_lcp, T_lcp;
    ASSERT_TRUE(lcp.Solve(normal, p.tool, p.F_hat_N, p.T_hat_N_m, &F_lcp, &T_lcp));
    EXPECT_GT(lcp.last_num_active(), 0);
    EXPECT_LT((F_friction - F_lcp).norm(), 1e-8 * std::max(F_lcp.norm(), 1e-9)) << seed;
    EXPECT_LT((T_friction - T_lcp).norm(), 1e-8 * std::max(T_lcp.norm(), 1e-12)) << seed;
  }
}

// Warm: the same rows for 40 steps while F̂ turns (the user moving between frames); every step
// converges to the dense reference of that step, in fewer sweeps than a cold start needs.
TEST(HapticFrictionSolver, WarmStartFollowsTheReferenceAsTheWrenchChanges) {
  LcpProblem p = MakeLcpProblem(30, 41, 0.3, 1.0, 3, 0.5);
  HapticFrictionSolver warm(90, kManySweeps);
  int warm_sweeps = 0, cold_sweeps = 0;
  for (int step = 0; step < 40; ++step) {
    const double phase = 0.15 * step;
    const Eigen::Vector3d F_hat =
        p.F_hat_N + 2.0 * Eigen::Vector3d(std::cos(phase), std::sin(phase), 0.3 * std::sin(phase));
    Eigen::Vector3d F_c, T_c;
    ASSERT_TRUE(warm.Solve(p.rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c));
    if (step > 0) warm_sweeps += warm.last_iterations();
    HapticFrictionSolver cold(90, kManySweeps);
    ASSERT_TRUE(cold.Solve(p.rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c));
    if (step > 0) cold_sweeps += cold.last_iterations();
    const DenseProblem dense = AssembleDense(p.rows, p.tool, F_hat, p.T_hat_N_m);
    const Eigen::VectorXd reference = SolveDense(dense, p.rows.friction_coefficient, kDt_s);
    EXPECT_LE((warm.last_impulses() - reference).norm(), 1e-8 * reference.norm()) << step;
    ExpectCoulomb(dense, p.rows.friction_coefficient, kDt_s, warm.last_impulses(), 1e-9,
                  "step " + std::to_string(step));
  }
  std::printf("sweeps over 39 steps: %d warm, %d cold\n", warm_sweeps, cold_sweeps);
  EXPECT_LT(warm_sweeps, cold_sweeps);
}

// Uncoupled contacts (ContactRows::num_uncoupled_rows, issue 13 item 5): converged steps equal
// the dense reference on the rows with zeros there, and satisfy Coulomb's law on it, while the
// solver's copy holds NaN there (never read); uncoupled contacts engage and release.
TEST(HapticFrictionSolver, UncoupledContactsMatchTheReferenceWithoutReadingTheirZeros) {
  const LcpProblem p = MakeLcpProblem(30, 43, 0.1, 1.0, 3, 0.5);
  ContactRows zeros = p.rows, poisoned = p.rows;
  UncoupleLastContacts(18, &zeros);
  UncoupleLastContacts(18, &poisoned, /*poison=*/true);
  HapticFrictionSolver solver(90, kManySweeps);
  Eigen::ArrayXi times_loaded = Eigen::ArrayXi::Zero(18);  // per uncoupled contact, over the steps
  constexpr int kSteps = 20;
  for (int step = 0; step < kSteps; ++step) {
    const double phase = 0.3 * step;
    const Eigen::Vector3d F_hat =
        p.F_hat_N +
        Eigen::Vector3d(3.0 * std::cos(phase), 3.0 * std::sin(phase), 8.0 * std::sin(phase));
    Eigen::Vector3d F_c, T_c;
    ASSERT_TRUE(solver.Solve(poisoned, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c)) << step;
    const DenseProblem dense = AssembleDense(zeros, p.tool, F_hat, p.T_hat_N_m);
    const Eigen::VectorXd reference = SolveDense(dense, zeros.friction_coefficient, kDt_s);
    EXPECT_LE((solver.last_impulses() - reference).norm(), 1e-8 * reference.norm()) << step;
    ExpectCoulomb(dense, zeros.friction_coefficient, kDt_s, solver.last_impulses(), 1e-9,
                  "step " + std::to_string(step));
    for (int i = 0; i < 18; ++i) times_loaded[i] += solver.last_impulses()[3 * (12 + i)] > 0.0;
  }
  const int switching = ((times_loaded > 0) && (times_loaded < kSteps)).count();
  std::printf("uncoupled contacts that engage and release: %d of 18\n", switching);
  EXPECT_GT(switching, 0) << "precondition: uncoupled contacts engage and release";
}

// Cut off after one sweep a step, every iterate is admissible (λ_n ≥ 0, |λ_t| ≤ μλ_n: the tool
// is never pulled), and pulling the tool away releases every contact within a few steps.
TEST(HapticFrictionSolver, OneSweepIsAdmissibleAndReleaseNeverPulls) {
  const LcpProblem p = MakeLcpProblem(40, 43, 0.5, 1.0, 3, 0.6);
  HapticFrictionSolver solver(120, 1);
  Eigen::Vector3d F_c, T_c;
  int released_at = -1;
  for (int step = 0; step < 60; ++step) {
    // Pressed for 20 steps, then pulled up hard (F̂ away from the body, whose normals point down
    // out of the tool).
    const Eigen::Vector3d F_hat =
        step < 20 ? p.F_hat_N : Eigen::Vector3d(p.F_hat_N + Eigen::Vector3d(0.0, 0.0, 400.0));
    ASSERT_TRUE(solver.Solve(p.rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c)) << step;
    EXPECT_EQ(solver.last_iterations(), 1);
    const Eigen::VectorXd lambda = solver.last_impulses();
    for (int i = 0; i < 40; ++i) {
      ASSERT_GE(lambda[3 * i], 0.0) << "step " << step << " contact " << i;
      ASSERT_LE(lambda.segment<2>(3 * i + 1).norm(), 0.6 * lambda[3 * i] * (1.0 + 1e-12) + 1e-300);
    }
    if (step == 19) {
      EXPECT_GT(solver.last_num_active(), 0);
    }
    if (step >= 20 && released_at < 0 && solver.last_num_active() == 0) released_at = step;
  }
  std::printf("released %d steps after the pull\n", released_at - 20);
  ASSERT_GE(released_at, 20);
  EXPECT_LE(released_at, 25);
  EXPECT_EQ(F_c, Eigen::Vector3d::Zero());
}

TEST(HapticFrictionSolver, RejectsRowsItCannotSolveWithZeroForce) {
  const LcpProblem friction = MakeLcpProblem(5, 51, 0.3, 1.0, 3, 0.5);
  const LcpProblem normal = MakeLcpProblem(5, 51, 0.3);
  HapticFrictionSolver solver(15, 100);
  Eigen::Vector3d F_c(1, 1, 1), T_c(1, 1, 1);
  EXPECT_FALSE(
      solver.Solve(normal.rows, normal.tool, normal.F_hat_N, normal.T_hat_N_m, &F_c, &T_c));
  EXPECT_EQ(F_c, Eigen::Vector3d::Zero());
  ContactRows bad = friction.rows;
  bad.W_body(0, 1) += 1.0;  // not symmetric
  EXPECT_FALSE(solver.Solve(bad, friction.tool, friction.F_hat_N, friction.T_hat_N_m, &F_c, &T_c));
  bad = friction.rows;
  bad.friction_coefficient[2] = std::nan("");
  EXPECT_FALSE(solver.Solve(bad, friction.tool, friction.F_hat_N, friction.T_hat_N_m, &F_c, &T_c));
  HapticFrictionSolver small(12, 100);  // 15 rows do not fit
  EXPECT_FALSE(
      small.Solve(friction.rows, friction.tool, friction.F_hat_N, friction.T_hat_N_m, &F_c, &T_c));
  // The frictionless solver refuses friction rows rather than read tangents as normals.
  HapticLcpSolver lcp(15);
  EXPECT_FALSE(
      lcp.Solve(friction.rows, friction.tool, friction.F_hat_N, friction.T_hat_N_m, &F_c, &T_c));
  // And recovers on good rows.
  EXPECT_TRUE(
      solver.Solve(friction.rows, friction.tool, friction.F_hat_N, friction.T_hat_N_m, &F_c, &T_c));
  EXPECT_GT(F_c.norm(), 0.0);
}

// The rows' cache: rows that differ only in μ, or only in a target, are new rows, solved as
// such (a cold solve's answer), not the previous rows' warm state.
TEST(HapticFrictionSolver, AChangeOfMuOrOfATargetAloneIsNewRows) {
  const LcpProblem p = MakeLcpProblem(12, 81, 0.3, 1.0, 3, 0.5);
  LcpProblem other_mu = p;
  other_mu.rows.friction_coefficient.setConstant(0.05);  // every sliding contact changes
  LcpProblem other_target = p;
  other_target.rows.body_rhs.array() += 0.02;
  for (const LcpProblem* q : {&other_mu, &other_target}) {
    HapticFrictionSolver warm(36, kManySweeps), cold(36, kManySweeps);
    Eigen::Vector3d F_first, F_warm, F_cold, T;
    ASSERT_TRUE(warm.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_first, &T));
    ASSERT_TRUE(warm.Solve(q->rows, q->tool, q->F_hat_N, q->T_hat_N_m, &F_warm, &T));
    ASSERT_TRUE(cold.Solve(q->rows, q->tool, q->F_hat_N, q->T_hat_N_m, &F_cold, &T));
    EXPECT_GT((F_cold - F_first).norm(), 1e-6) << "precondition: the change matters";
    EXPECT_LT((F_warm - F_cold).norm(), 1e-8 * F_cold.norm());
  }
}

// The row cache with uncoupled contacts (ContactRows::num_uncoupled_rows), rows unstamped: a
// change the solvers would read (a coupled entry, an uncoupled contact's own block, the split
// itself) makes new rows; a change where the rows declare zeros (never read) does not. And
// HasConsistentShape refuses a split that is not whole contacts of the rows.
TEST(ContactRowCache, ComparesWhatTheSolversReadWithUncoupledContacts) {
  LcpProblem p = MakeLcpProblem(10, 91, 0.2, 1.0, 3, 0.5);
  UncoupleLastContacts(4, &p.rows);  // rows 18..29 uncoupled
  ContactRowCache cache(30);
  ASSERT_TRUE(cache.Take(p.rows));
  EXPECT_TRUE(cache.Holds(p.rows));
  const auto changed = [&](auto change) {
    ContactRows rows = p.rows;
    change(&rows);
    return !cache.Holds(rows);
  };
  EXPECT_TRUE(changed([](ContactRows* r) { r->W_body(4, 1) += 1e-9; }));    // coupled block
  EXPECT_TRUE(changed([](ContactRows* r) { r->W_body(23, 22) += 1e-9; }));  // uncoupled, own block
  EXPECT_TRUE(changed([](ContactRows* r) { r->W_body(21, 23) += 1e-9; }));  // own, upper
  EXPECT_FALSE(changed([](ContactRows* r) { r->W_body(25, 3) = 7.0; }));    // declared zero
  EXPECT_TRUE(changed([](ContactRows* r) { r->num_uncoupled_rows = 9; }));
  for (const int bad : {-3, 2, 33}) {
    ContactRows rows = p.rows;
    rows.num_uncoupled_rows = bad;
    EXPECT_FALSE(HasConsistentShape(rows)) << bad;
  }
  // The solvers refuse such rows with zero force.
  ContactRows rows = p.rows;
  rows.num_uncoupled_rows = 2;
  HapticFrictionSolver solver(30, 10);
  Eigen::Vector3d F_c(1, 1, 1), T_c(1, 1, 1);
  EXPECT_FALSE(solver.Solve(rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_c, &T_c));
  EXPECT_EQ(F_c, Eigen::Vector3d::Zero());
}

// Stamped rows (ContactRows::stamp) are compared by their stamp alone: rows changed in place
// without a new stamp are, by the contract, the cached ones; a new stamp makes them new rows,
// solved as a cold solver solves them. Both solvers, friction and frictionless.
TEST(ContactRowsStamp, EqualStampsAreTheSameRowsAndANewStampIsNewRows) {
  for (const int rows_per_contact : {3, 1}) {
    LcpProblem p = MakeLcpProblem(12, 83, 0.3, 1.0, rows_per_contact, 0.5);
    StampNewContactRows(&p.rows);
    const ContactRows original = p.rows;
    HapticLcpSolver warm(36, kManySweeps), cold_original(36, kManySweeps),
        cold_changed(36, kManySweeps);
    Eigen::Vector3d F_warm, F_original, F_changed, T;
    ASSERT_TRUE(warm.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_warm, &T));
    p.rows.body_rhs.array() += 0.02;  // in place, stamp kept: the contract says "unchanged"
    ASSERT_TRUE(warm.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_warm, &T));
    ContactRows unstamped = original;
    unstamped.stamp = 0;
    ASSERT_TRUE(cold_original.Solve(unstamped, p.tool, p.F_hat_N, p.T_hat_N_m, &F_original, &T));
    EXPECT_LT((F_warm - F_original).norm(), 1e-8 * F_original.norm()) << rows_per_contact;
    StampNewContactRows(&p.rows);
    EXPECT_GT(p.rows.stamp, original.stamp);
    ASSERT_TRUE(warm.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_warm, &T));
    unstamped = p.rows;
    unstamped.stamp = 0;
    ASSERT_TRUE(cold_changed.Solve(unstamped, p.tool, p.F_hat_N, p.T_hat_N_m, &F_changed, &T));
    EXPECT_GT((F_changed - F_original).norm(), 1e-6) << "precondition: the change matters";
    EXPECT_LT((F_warm - F_changed).norm(), 1e-8 * F_changed.norm()) << rows_per_contact;
  }
}

// The lcp mode's solver hands friction rows to its friction solve (built with sweeps), and
// reports that solve; without sweeps it refuses them, leaving no impulses from an older solve.
TEST(HapticLcpSolver, HandsFrictionRowsToItsFrictionSolve) {
  const LcpProblem p = MakeLcpProblem(10, 91, 0.3, 1.0, 3, 0.5);
  HapticLcpSolver lcp(30, 50);
  HapticFrictionSolver friction(30, 50);
  EXPECT_EQ(lcp.friction_sweeps(), 50);
  Eigen::Vector3d F_lcp, T_lcp, F_friction, T_friction;
  ASSERT_TRUE(lcp.Prepare(p.rows, p.tool));
  ASSERT_TRUE(lcp.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_lcp, &T_lcp));
  ASSERT_TRUE(friction.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_friction, &T_friction));
  EXPECT_EQ(F_lcp, F_friction);
  EXPECT_EQ(T_lcp, T_friction);
  EXPECT_EQ(lcp.last_impulses(), friction.last_impulses());
  EXPECT_EQ(lcp.last_iterations(), friction.last_iterations());
  EXPECT_EQ(lcp.last_num_active(), friction.last_num_active());
  EXPECT_EQ(lcp.last_num_factorizations(), 0);
  // Without sweeps: normal rows solve, then friction rows are refused with no impulses left.
  const LcpProblem normal = MakeLcpProblem(10, 91, 0.3);
  HapticLcpSolver frictionless(30);
  EXPECT_EQ(frictionless.friction_sweeps(), 0);
  ASSERT_TRUE(frictionless.Solve(normal.rows, normal.tool, normal.F_hat_N, normal.T_hat_N_m, &F_lcp,
                                 &T_lcp));
  EXPECT_EQ(frictionless.last_impulses().size(), 10);
  EXPECT_FALSE(frictionless.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_lcp, &T_lcp));
  EXPECT_EQ(F_lcp, Eigen::Vector3d::Zero());
  EXPECT_EQ(frictionless.last_impulses().size(), 0);
}

TEST(HapticFrictionSolver, AllocatesNothingAt510Rows) {
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations not counted (sanitizer)";
  std::vector<LcpProblem> problems = {
      MakeLcpProblem(170, 61, 0.3, 1.0, 3, 0.5), MakeLcpProblem(100, 62, 0.1, 1.0, 3, 1.0),
      MakeLcpProblem(170, 63, 1.0, 30.0, 3, 0.2), MakeLcpProblem(170, 64, 0.3, 1.0, 3, 0.5)};
  UncoupleLastContacts(120, &problems.back().rows);  // the structured products too
  std::vector<ToolStepSystem> tools;
  for (int k = 0; k < 4; ++k) tools.push_back(MakeTool(0.05 * k));
  HapticFrictionSolver solver(512, 20);
  Eigen::Vector3d F_c, T_c;
  int failures = 0, active = 0;
  AllocationCounter counter;
  for (int step = 0; step < 120; ++step) {
    const LcpProblem& p = problems[(step / 30) % problems.size()];
    if (step % 30 == 0 && step > 0 && !solver.Prepare(p.rows)) ++failures;
    const Eigen::Vector3d F_hat = p.F_hat_N + Eigen::Vector3d(std::cos(0.2 * step), 0.0, 0.0);
    if (!solver.Solve(p.rows, tools[step % tools.size()], F_hat, p.T_hat_N_m, &F_c, &T_c))
      ++failures;
    active = std::max(active, solver.last_num_active());
  }
  const std::int64_t allocations = counter.count();
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(failures, 0);
  EXPECT_GT(active, 50);  // the column updates over all 510 rows were exercised
}

}  // namespace
}  // namespace hapsim::contact
