// The hybrid mode's solve (contact/haptic_lcp_solver.h, hold_frame_contacts): the frame's active
// rows held as equalities, its other rows unilateral (a mixed LCP), against independent values:
//  - enumeration: every subset of the free rows, each solved densely with the held rows by LU on
//    the assembled W; the one subset whose solution meets the mixed LCP's conditions is the
//    answer (unique, W's symmetric part positive definite); a held row that pulls past the
//    frame's push on it is released and the enumeration repeated, until none does;
//  - the linear contact model (MakeLinearContactModel) on the held rows when no free row engages,
//    also while a held row pulls (λ < 0), which the plain lcp solve would not allow;
//  - no heap allocation after construction.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "contact/contact_jacobian.h"
#include "contact/haptic_lcp_solver.h"
#include "contact/linear_contact_model.h"
#include "tests/allocation_counter.h"
#include "tests/contact/haptic_test_problems.h"

namespace hapsim::contact {
namespace {

// Both methods are exact; they differ by round-off amplified by W's condition number (≤ 1e5 for
// these problems).
constexpr double kRelativeTolerance = 1e-9;

// λ with the equality Δt W_SS λ_S = rhs_S on the rows `set` and zero elsewhere (dense LU, or
// the minimum-norm solution by a complete orthogonal decomposition for possibly dependent rows).
// Returns the residual of that equality.
double SolveOnSubset(const DenseProblem& dense, double dt_s, const std::vector<int>& set,
                     bool minimum_norm, Eigen::VectorXd* lambda) {
  const int k = static_cast<int>(set.size());
  Eigen::MatrixXd W_set(k, k);
  Eigen::VectorXd rhs_set(k);
  for (int a = 0; a < k; ++a) {
    rhs_set[a] = dense.rhs[set[a]];
    for (int b = 0; b < k; ++b) W_set(a, b) = dt_s * dense.W(set[a], set[b]);
  }
  *lambda = Eigen::VectorXd::Zero(dense.rhs.size());
  if (k == 0) return 0.0;
  const Eigen::VectorXd x = minimum_norm ? W_set.completeOrthogonalDecomposition().solve(rhs_set)
                                         : Eigen::VectorXd(W_set.partialPivLu().solve(rhs_set));
  for (int a = 0; a < k; ++a) (*lambda)[set[a]] = x[a];
  return (W_set * x - rhs_set).norm();
}

// The mixed LCP by enumeration: for each subset A of the free rows, λ on H ∪ A from
// Δt W_{(H∪A)(H∪A)} λ = rhs (dense LU), zero elsewhere; the answer is the subset with λ_A ≥ 0
// and c = Δt W λ − rhs ≥ 0 on the free rows outside A. 2^free subsets: small problems only.
Eigen::VectorXd SolveByEnumeration(const DenseProblem& dense, double dt_s,
                                   const std::vector<bool>& held) {
  const int n = static_cast<int>(held.size());
  std::vector<int> free_rows;
  for (int i = 0; i < n; ++i)
    if (!held[i]) free_rows.push_back(i);
  const int num_free = static_cast<int>(free_rows.size());
  const double tolerance = 1e-12 * (1.0 + dense.rhs.cwiseAbs().maxCoeff());
  Eigen::VectorXd found;
  int num_found = 0;
  for (unsigned mask = 0; mask < (1u << num_free); ++mask) {
    std::vector<int> set;
    for (int i = 0; i < n; ++i)
      if (held[i]) set.push_back(i);
    for (int f = 0; f < num_free; ++f)
      if (mask & (1u << f)) set.push_back(free_rows[f]);
    Eigen::VectorXd lambda;
    SolveOnSubset(dense, dt_s, set, /*minimum_norm=*/false, &lambda);
    const Eigen::VectorXd c = dt_s * dense.W * lambda - dense.rhs;
    bool ok = true;
    for (int f = 0; f < num_free; ++f) {
      const int i = free_rows[f];
      ok = ok && ((mask & (1u << f)) ? lambda[i] >= -tolerance : c[i] >= -tolerance);
    }
    if (ok) {
      found = lambda;
      ++num_found;
    }
  }
  EXPECT_EQ(num_found, 1) << "the mixed LCP's solution is unique";
  return found;
}

// The plain LCP (every row unilateral) with possibly dependent rows: every subset whose equality
// block is non-singular (complete orthogonal decomposition, minimum norm) and meets the
// conditions; returns the first (the force J_vᵀλ is the same for all of them).
Eigen::VectorXd SolveByEnumerationAllowingTies(const DenseProblem& dense, double dt_s) {
  const int n = static_cast<int>(dense.rhs.size());
  const double tolerance = 1e-10 * (1.0 + dense.rhs.cwiseAbs().maxCoeff());
  for (unsigned mask = 0; mask < (1u << n); ++mask) {
    std::vector<int> set;
    for (int i = 0; i < n; ++i)
      if (mask & (1u << i)) set.push_back(i);
    Eigen::VectorXd lambda;
    const double residual = SolveOnSubset(dense, dt_s, set, /*minimum_norm=*/true, &lambda);
    if (residual > tolerance) continue;  // no solution on this set (dependent, inconsistent)
    const Eigen::VectorXd c = dt_s * dense.W * lambda - dense.rhs;
    if (lambda.minCoeff() >= -tolerance && c.minCoeff() >= -tolerance) return lambda;
  }
  ADD_FAILURE() << "no solution found";
  return Eigen::VectorXd::Zero(n);
}

// The solver's law with its releases (HapticLcpSolver: a held row may pull by at most the frame's
// impulse on it), from exact solves: the mixed LCP by enumeration, then every held row pulling
// past its frame impulse released (in `held`, which keeps them released, as the solver does until
// new rows come), and again until no held row does.
Eigen::VectorXd SolveByEnumerationWithReleases(const DenseProblem& dense, double dt_s,
                                               const Eigen::VectorXd& lambda_frame_N,
                                               std::vector<bool>* held) {
  while (true) {
    const Eigen::VectorXd lambda = SolveByEnumeration(dense, dt_s, *held);
    bool released = false;
    for (size_t i = 0; i < held->size(); ++i) {
      if (!(*held)[i] || !(lambda[i] < -lambda_frame_N[i])) continue;
      (*held)[i] = false;
      released = true;
    }
    if (!released) return lambda;
  }
}

// `rows` with the frame's impulses set so that `held` are the frame's active rows, each with
// `push_N`: what a held row may pull before it is released.
void MarkFrameActive(const std::vector<bool>& held, ContactRows* rows, double push_N = 1.0) {
  rows->lambda_frame_N = Eigen::VectorXd::Zero(rows->num_rows());
  for (int i = 0; i < rows->num_rows(); ++i)
    if (held[i]) rows->lambda_frame_N[i] = push_N;
}

// Frame impulses no held row of these random problems pulls past: the mixed LCP alone.
constexpr double kNoReleasePush_N = 1e3;

TEST(HapticHybridSolve, MatchesEnumerationOfTheMixedLcp) {
  int num_pulling = 0, num_free_engaged = 0, num_released = 0;
  for (const int n : {6, 9, 12}) {
    for (unsigned seed = 1; seed <= 6; ++seed) {
      const LcpProblem p = MakeLcpProblem(n, 1000 * n + seed, 0.0, 1.0);
      std::vector<bool> held(n, false);
      for (int i = 0; i < n; i += 3) held[i] = true;  // a third held, the rest free
      ContactRows rows = p.rows;
      MarkFrameActive(held, &rows);
      HapticLcpSolver solver(16, 0, /*hold_frame_contacts=*/true);
      for (const double swing : {0.0, 2.0, -2.0}) {  // F̂ changes over the frame's steps
        const Eigen::Vector3d F_hat = p.F_hat_N + swing * Eigen::Vector3d(0.2, -0.1, 1.0);
        Eigen::Vector3d F_c, T_c;
        const std::string where = "n " + std::to_string(n) + " seed " + std::to_string(seed) +
                                  " swing " + std::to_string(swing);
        ASSERT_TRUE(solver.Solve(rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c)) << where;
        EXPECT_LT(solver.last_residual(), 1e-10) << where;
        const DenseProblem dense = AssembleDense(rows, p.tool, F_hat, p.T_hat_N_m);
        const int num_held = static_cast<int>(std::count(held.begin(), held.end(), true));
        const Eigen::VectorXd expected =
            SolveByEnumerationWithReleases(dense, p.tool.dt_s, rows.lambda_frame_N, &held);
        num_released += num_held - static_cast<int>(std::count(held.begin(), held.end(), true));
        const Eigen::VectorXd lambda = solver.last_impulses();
        EXPECT_LE((lambda - expected).norm(), kRelativeTolerance * expected.norm()) << where;
        const double F_scale = expected.cwiseAbs().sum();
        EXPECT_LE((F_c - rows.J_v.transpose() * expected).norm(), kRelativeTolerance * F_scale)
            << where;
        for (int i = 0; i < n; ++i) {
          num_pulling += held[i] && expected[i] < 0.0;
          num_free_engaged += !held[i] && expected[i] > 0.0;
        }
      }
    }
  }
  // The cases exercise every part of the law: held rows that pull, held rows released, free rows
  // that engage.
  EXPECT_GT(num_pulling, 5);
  EXPECT_GT(num_released, 5);
  EXPECT_GT(num_free_engaged, 5);
}

// Free rows far from engaging (a large separating target): the solve is the linear contact model
// of the held rows, pulling rows included, at every F̂.
TEST(HapticHybridSolve, WithNoFreeRowEngagedIsTheLinearContactModel) {
  const int n = 20;
  const LcpProblem p = MakeLcpProblem(n, 77, 0.0, 1.0);
  std::vector<bool> held(n, false);
  std::vector<int> held_rows;
  for (int i = 0; i < n; i += 2) held[i] = true, held_rows.push_back(i);
  ContactRows rows = p.rows;
  for (int i = 0; i < n; ++i)
    if (!held[i]) rows.body_rhs[i] = -10.0;  // each would need 10 m/s more approach to engage
  MarkFrameActive(held, &rows, kNoReleasePush_N);
  const int k = static_cast<int>(held_rows.size());
  ContactJacobian J;
  J.J_v.resize(k, 3);
  J.J_w.resize(k, 3);
  Eigen::VectorXd body_rhs(k);
  for (int a = 0; a < k; ++a) {
    J.J_v.row(a) = rows.J_v.row(held_rows[a]);
    J.J_w.row(a) = rows.J_w.row(held_rows[a]);
    body_rhs[a] = rows.body_rhs[held_rows[a]];
  }
  const ContactRows held_only = MakeContactRows(J, rows.W_body, held_rows, body_rhs);
  const Eigen::MatrixXd W = CalcToolDelassus(J, p.tool) + held_only.W_body;
  const LinearContactModel model = MakeLinearContactModel(J, W, p.tool, held_only.body_rhs);
  HapticLcpSolver hybrid(n, 0, /*hold_frame_contacts=*/true);
  HapticLcpSolver lcp(n);
  int num_pulling = 0;
  for (const double scale : {0.0, 1.0, -1.0, 3.0}) {
    const Eigen::Vector3d F_hat = p.F_hat_N + scale * Eigen::Vector3d(0.5, -1.0, 2.0);
    Eigen::Vector3d F_c, T_c, F_model, T_model, F_lcp, T_lcp;
    ASSERT_TRUE(hybrid.Solve(rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c)) << scale;
    EvaluateLinearContactModel(model, F_hat, p.T_hat_N_m, &F_model, &T_model);
    EXPECT_LT((F_c - F_model).norm(), kRelativeTolerance * (1.0 + F_model.norm())) << scale;
    EXPECT_LT((T_c - T_model).norm(), kRelativeTolerance * (1.0 + T_model.norm())) << scale;
    for (int i = 0; i < n; ++i) {
      if (!held[i]) {
        EXPECT_EQ(hybrid.last_impulses()[i], 0.0) << scale << " row " << i;
      }
      num_pulling += held[i] && hybrid.last_impulses()[i] < 0.0;
    }
    // The plain lcp solve lets a pulling row go: where one pulls, the two differ.
    ASSERT_TRUE(lcp.Solve(rows, p.tool, F_hat, p.T_hat_N_m, &F_lcp, &T_lcp));
    EXPECT_GE(lcp.last_impulses().minCoeff(), 0.0);
  }
  EXPECT_GT(num_pulling, 0) << "the case must include a held row that pulls";
}

// The step's own targets (Solve's `targets`: the hybrid step's free rows follow the tool): a warm
// solver, and one prepared on the rows' own body_rhs, solve each step's targets as a fresh solver
// solves rows whose body_rhs are those targets, and as enumeration does. Exercises RefreshTargets
// (same base, new h and q) and the border built on earlier targets.
TEST(HapticHybridSolve, PerStepTargetsAreSolvedExactly) {
  const int n = 10;
  const LcpProblem p = MakeLcpProblem(n, 4242, 0.0, 1.0);
  std::vector<bool> held(n, false);
  for (int i = 0; i < n; i += 3) held[i] = true;
  ContactRows rows = p.rows;
  MarkFrameActive(held, &rows, kNoReleasePush_N);
  StampNewContactRows(&rows);
  HapticLcpSolver warm(16, 0, true), prepared(16, 0, true);
  ASSERT_TRUE(prepared.Prepare(rows, MakeTool(0.3)));
  for (int step = 0; step < 12; ++step) {
    Eigen::VectorXd targets = rows.body_rhs;
    for (int i = 0; i < n; ++i)  // free rows' targets move, as a tool approaching them would
      if (!held[i]) targets[i] += 0.05 * std::sin(0.7 * step + i);
    ContactRows as_rhs = rows;  // the same problem with the targets as its body_rhs
    as_rhs.body_rhs = targets;
    as_rhs.stamp = 0;
    HapticLcpSolver fresh(16, 0, true);
    Eigen::Vector3d F_warm, F_prepared, F_fresh, T;
    const std::string where = "step " + std::to_string(step);
    ASSERT_TRUE(warm.Solve(rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_warm, &T, &targets)) << where;
    ASSERT_TRUE(prepared.Solve(rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_prepared, &T, &targets))
        << where;
    ASSERT_TRUE(fresh.Solve(as_rhs, p.tool, p.F_hat_N, p.T_hat_N_m, &F_fresh, &T)) << where;
    const Eigen::VectorXd expected = SolveByEnumeration(
        AssembleDense(as_rhs, p.tool, p.F_hat_N, p.T_hat_N_m), p.tool.dt_s, held);
    const double scale = kRelativeTolerance * expected.norm();
    EXPECT_LE((warm.last_impulses() - expected).norm(), scale) << where;
    EXPECT_LE((prepared.last_impulses() - expected).norm(), scale) << where;
    EXPECT_LE((fresh.last_impulses() - expected).norm(), scale) << where;
    if (step == 0) {
      EXPECT_GT(warm.last_num_factorizations(), 0);  // then borders, new h and q
    }
  }
}

// Held rows that are dependent (the frame found a contact twice active: it admits redundant
// contacts) have no equality solution to hold: the rows are then solved as the lcp mode solves
// them, and the solve does not fail (a fall-back to the linear model would lose the free rows).
TEST(HapticHybridSolve, DependentHeldRowsAreSolvedUnilaterally) {
  const LcpProblem p = MakeLcpProblem(8, 99, 0.5, 1.0);
  ContactRows rows = p.rows;
  // Row 7 becomes a copy of row 0, in J, W_body and body_rhs: the same constraint twice.
  const int n = rows.num_rows();
  rows.J_v.row(7) = rows.J_v.row(0);
  rows.J_w.row(7) = rows.J_w.row(0);
  rows.W_body.row(7) = rows.W_body.row(0);
  rows.W_body.col(7) = rows.W_body.col(0);
  rows.body_rhs[7] = rows.body_rhs[0];
  std::vector<bool> held(n, false);
  held[0] = held[7] = held[3] = true;
  MarkFrameActive(held, &rows);
  HapticLcpSolver hybrid(16, 0, true);
  Eigen::Vector3d F_hybrid, F_lcp, T;
  ASSERT_TRUE(hybrid.Solve(rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_hybrid, &T));
  const Eigen::VectorXd expected = SolveByEnumerationAllowingTies(
      AssembleDense(rows, p.tool, p.F_hat_N, p.T_hat_N_m), p.tool.dt_s);
  // The force is unique though the split between the twin rows is not.
  EXPECT_LE((F_hybrid - rows.J_v.transpose() * expected).norm(),
            1e-8 * (1.0 + expected.cwiseAbs().sum()));
  EXPECT_GE(hybrid.last_impulses().minCoeff(), 0.0);
}

// The case that called for the release (two_organs, exact compliance: ±1e10 N and 26–260 N on the
// tool): a held row and a free near-twin (W's rows alike to ~1e-8, as two tool points on one body
// face) whose target asks for a little more separation. Held, the row and its
// twin meet with opposite impulses ∝ 1/(twin distance)²; released, the held row is unilateral and
// the pair's force is that of the plain lcp solve.
TEST(HapticHybridSolve, HeldRowPullingAgainstAFreeTwinIsReleased) {
  const int n = 6;
  const LcpProblem p = MakeLcpProblem(n, 31, 0.0, 1.0);
  ContactRows rows = p.rows;
  // W_body = B Bᵀ with row 1 of B row 0's plus 1e-4 of another: W's rows 0 and 1 alike to ~1e-8.
  Eigen::MatrixXd B = rows.W_body.llt().matrixL();
  B.row(1) = B.row(0) + 1e-4 * B.row(2);
  rows.W_body = B * B.transpose();
  rows.J_v.row(1) = rows.J_v.row(0);
  rows.J_w.row(1) = rows.J_w.row(0);
  rows.body_rhs[0] = 0.2;
  rows.body_rhs[1] = 0.25;  // the twin asks to separate 0.05 m/s faster
  std::vector<bool> held(n, false);
  held[0] = held[3] = true;
  MarkFrameActive(held, &rows, 0.5);
  const DenseProblem dense = AssembleDense(rows, p.tool, p.F_hat_N, p.T_hat_N_m);
  const Eigen::VectorXd held_answer = SolveByEnumeration(dense, p.tool.dt_s, held);
  ASSERT_LT(held_answer[0], -1e3) << "the case must hold its row against the twin";
  HapticLcpSolver hybrid(16, 0, /*hold_frame_contacts=*/true), lcp(16);
  Eigen::Vector3d F_hybrid, F_lcp, T;
  ASSERT_TRUE(hybrid.Solve(rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_hybrid, &T));
  std::vector<bool> kept = held;
  const Eigen::VectorXd expected =
      SolveByEnumerationWithReleases(dense, p.tool.dt_s, rows.lambda_frame_N, &kept);
  EXPECT_FALSE(kept[0]);
  EXPECT_LE((hybrid.last_impulses() - expected).norm(), 1e-7 * expected.norm());
  EXPECT_GE(hybrid.last_impulses()[0], 0.0);
  EXPECT_LT(hybrid.last_impulses().cwiseAbs().maxCoeff(), 1e2);
  // The release persists over the frame's next steps (a row released is not held again).
  ASSERT_TRUE(hybrid.Solve(rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_hybrid, &T));
  EXPECT_LE((hybrid.last_impulses() - expected).norm(), 1e-7 * expected.norm());
}

TEST(HapticHybridSolve, AllocatesNothingAfterConstruction) {
  if (!AllocationCounter::enabled()) GTEST_SKIP() << "allocations not counted (sanitizer)";
  std::vector<LcpProblem> problems = {MakeLcpProblem(125, 21), MakeLcpProblem(60, 22, 0.3, 30.0),
                                      MakeLcpProblem(150, 23)};
  for (LcpProblem& p : problems) {
    std::vector<bool> held(p.rows.num_rows(), false);
    for (int i = 0; i < p.rows.num_rows(); i += 4) held[i] = true;
    MarkFrameActive(held, &p.rows);
  }
  HapticLcpSolver solver(150, 0, /*hold_frame_contacts=*/true);
  Eigen::Vector3d F_c, T_c;
  int failures = 0;
  AllocationCounter counter;
  for (int step = 0; step < 240; ++step) {
    const LcpProblem& p = problems[(step / 40) % problems.size()];
    const double phase = 0.3 * step;
    const Eigen::Vector3d F_hat =
        p.F_hat_N + 3.0 * Eigen::Vector3d(std::cos(phase), std::sin(phase), 0.0);
    failures += !solver.Solve(p.rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c);
  }
  EXPECT_EQ(counter.count(), 0);
  EXPECT_EQ(failures, 0);
}

}  // namespace
}  // namespace hapsim::contact
