// Contact response and the linear contact model against independent values:
//  - the equality solve through W against the paper's full KKT system (eq. 10) solved densely,
//    exact and with its default compliance; nearly redundant rows against the 2 × 2 closed form;
//  - projected Gauss–Seidel against an exhaustive enumeration of LCP active sets;
//  - Coulomb friction on a decoupled contact against its closed form (stick / slide);
//  - the linear contact model against re-solving the constraints under perturbed F̂, T̂.
// Small synthetic systems: a 4-node "body" with a random SPD A_u, a tool with a hand-set
// ToolStepSystem, contacts with random normals and points.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

#include "contact/contact_jacobian.h"
#include "contact/contact_solver.h"
#include "contact/linear_contact_model.h"

namespace hapsim::contact {
namespace {

constexpr int kNumNodes = 4;
constexpr int kNumDofs = 3 * kNumNodes;
constexpr double kDt_s = 1e-3;

struct Problem {
  ToolStepSystem tool;
  ToolState tool_state;
  Eigen::MatrixXd A_u;            // body system matrix (dense, SPD)
  Eigen::VectorXd u_dot_m_s;      // body velocities (frozen)
  Eigen::VectorXd body_force_dt;  // Δt F̃_u
  std::vector<Contact> contacts;
  Eigen::VectorXd b;  // stabilisation targets
};

// A reproducible random problem. `symmetric_tool` makes A_L's coupling term symmetric so W is
// symmetric (needed for the LCP enumeration to be a fair reference for PGS).
Problem MakeProblem(int num_contacts, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto random3 = [&] { return Eigen::Vector3d(unit(rng), unit(rng), unit(rng)); };
  Problem p;
  p.tool.dt_s = kDt_s;
  const double m_kg = 0.05, k_N_m = 2000.0, b_N_s_m = 2.0;
  p.tool.A_v = (m_kg + kDt_s * b_N_s_m + kDt_s * kDt_s * k_N_m) * Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d inertia = Eigen::Vector3d(2e-5, 3e-5, 1e-5).asDiagonal();
  p.tool.M_inv_W = inertia.inverse();
  const Eigen::Matrix3d C = (kDt_s * 0.01 + kDt_s * kDt_s * 1.0) * Eigen::Matrix3d::Identity();
  p.tool.A_L = Eigen::Matrix3d::Identity() + C * p.tool.M_inv_W;
  p.tool.F_tilde_N = Eigen::Vector3d(0.3, -0.2, -3.0);
  p.tool.T_tilde_N_m = Eigen::Vector3d(0.01, 0.02, -0.005);
  p.tool_state.x_W_m = Eigen::Vector3d(0.0, 0.0, 0.02);
  p.tool_state.v_W_m_s = 0.05 * random3();
  p.tool_state.L_W_kg_m2_s = 1e-6 * random3();
  const Eigen::MatrixXd R = Eigen::MatrixXd::Random(kNumDofs, kNumDofs);
  p.A_u = R * R.transpose() * 1e-3 + 1e-2 * Eigen::MatrixXd::Identity(kNumDofs, kNumDofs);
  p.u_dot_m_s = 0.01 * Eigen::VectorXd::Random(kNumDofs);
  p.body_force_dt = 1e-4 * Eigen::VectorXd::Random(kNumDofs);
  for (int i = 0; i < num_contacts; ++i) {
    Contact c;
    c.n_W = (random3() + Eigen::Vector3d(0, 0, -2.0)).normalized();  // tool pressing down
    c.p_tool_W_m = p.tool_state.x_W_m + 0.01 * random3();
    const double w = 0.5 + 0.4 * unit(rng);
    c.SetBodyNodes({i % kNumNodes, (i + 1) % kNumNodes}, {w, 1.0 - w});
    c.gap_m = 1e-4 * unit(rng);
    p.contacts.push_back(c);
    p.b.conservativeResize(i + 1);
    p.b[i] = -0.2 * c.gap_m / kDt_s;
  }
  return p;
}

struct Assembled {
  ContactJacobian J;
  Eigen::MatrixXd W;
  Eigen::VectorXd c_free;  // separating velocity after the collision-free update
};

Assembled Assemble(const Problem& p, int rows_per_contact) {
  Assembled a;
  a.J = CalcContactJacobian(p.contacts, p.tool_state.x_W_m, rows_per_contact, kNumDofs,
                            std::vector<std::uint8_t>(kNumDofs, 0));
  const Eigen::MatrixXd J_u = Eigen::MatrixXd(a.J.J_u);
  a.W = CalcToolDelassus(a.J, p.tool) + J_u * p.A_u.ldlt().solve(J_u.transpose());
  const Eigen::Vector3d v_free =
      p.tool.A_v.inverse() * kDt_s * p.tool.F_tilde_N + p.tool_state.v_W_m_s;
  const Eigen::Vector3d L_free =
      p.tool.A_L.inverse() * kDt_s * p.tool.T_tilde_N_m + p.tool_state.L_W_kg_m2_s;
  const Eigen::VectorXd u_free = p.u_dot_m_s + p.A_u.ldlt().solve(p.body_force_dt);
  a.c_free = a.J.J_v * v_free + a.J.J_w * p.tool.M_inv_W * L_free + J_u * u_free;
  return a;
}

// The exact law (ε = 0) and the default, whose compliance ε W_ii per row is the KKT system's
// lower-right block Δt ε diag W (c_post + Δt ε W_ii λ_i = b_i).
class EqualityCompliance : public ::testing::TestWithParam<double> {};

TEST_P(EqualityCompliance, EqualitySolveMatchesFullKktSystem) {
  const double epsilon = GetParam();
  const Problem p = MakeProblem(5, 1);
  const Assembled a = Assemble(p, 1);
  ContactSolveOptions options{ContactLaw::kEquality};
  options.equality_compliance = epsilon;
  Eigen::VectorXd lambda;
  const ContactSolveReport report =
      SolveContactImpulses(a.W, p.b - a.c_free, kDt_s, 1, options, &lambda);
  EXPECT_LT(report.residual, 1e-12);

  // The paper's eq. (10): unknowns (Δv, ΔL, Δu̇, λ), assembled and solved densely.
  const int n = 5, size = 6 + kNumDofs + n;
  const Eigen::MatrixXd J_u = Eigen::MatrixXd(a.J.J_u);
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(size, size);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(size);
  K.block<3, 3>(0, 0) = p.tool.A_v;
  K.block(0, 6 + kNumDofs, 3, n) = -kDt_s * a.J.J_v.transpose();
  K.block<3, 3>(3, 3) = p.tool.A_L;
  K.block(3, 6 + kNumDofs, 3, n) = -kDt_s * a.J.J_w.transpose();
  K.block(6, 6, kNumDofs, kNumDofs) = p.A_u;
  K.block(6, 6 + kNumDofs, kNumDofs, n) = -kDt_s * J_u.transpose();
  K.block(6 + kNumDofs, 0, n, 3) = a.J.J_v;
  K.block(6 + kNumDofs, 3, n, 3) = a.J.J_w * p.tool.M_inv_W;
  K.block(6 + kNumDofs, 6, n, kNumDofs) = J_u;
  K.block(6 + kNumDofs, 6 + kNumDofs, n, n).diagonal() = kDt_s * epsilon * a.W.diagonal();
  rhs.segment<3>(0) = kDt_s * p.tool.F_tilde_N;
  rhs.segment<3>(3) = kDt_s * p.tool.T_tilde_N_m;
  rhs.segment(6, kNumDofs) = p.body_force_dt;
  rhs.tail(n) = p.b - a.J.J_v * p.tool_state.v_W_m_s -
                a.J.J_w * p.tool.M_inv_W * p.tool_state.L_W_kg_m2_s - J_u * p.u_dot_m_s;
  const Eigen::VectorXd solution = K.fullPivLu().solve(rhs);
  EXPECT_LT((solution.tail(n) - lambda).norm(), 1e-9 * lambda.norm());
}

INSTANTIATE_TEST_SUITE_P(ExactAndDefault, EqualityCompliance,
                         ::testing::Values(0.0, ContactSolveOptions{}.equality_compliance));

// Two rows that are nearly one (a point and its neighbour 10⁻⁶ of a cell away, as a rim point
// beside a face's own node): W = w [[1, 1 − η], [1 − η, 1]], η = 10⁻¹². The exact solve splits
// targets 10⁻⁶ apart into forces ~10⁶ times the load, of both signs; with the compliance ε w the
// pair's sum and difference follow from the 2 × 2 system in closed form, and the difference is
// bounded by that of the targets over Δt ε w. (W's diagonal is w: ε diag W = ε w I.)
TEST(ContactResponse, NearlyRedundantEqualityRowsShareTheLoad) {
  const double w = 2.0e-3, eta = 1e-12, r = 0.01, dr = 1e-6 * r;
  Eigen::Matrix2d W;
  W << w, (1.0 - eta) * w, (1.0 - eta) * w, w;
  const Eigen::Vector2d rhs(r, r + dr);
  ContactSolveOptions options{ContactLaw::kEquality};
  Eigen::VectorXd lambda;
  SolveContactImpulses(W, rhs, kDt_s, 1, options, &lambda);
  const double epsilon = options.equality_compliance;
  const double sum = 2.0 * r + dr, difference = -dr;
  // Δt (W + ε w I) on (1, 1) and (1, −1): eigenvalues Δt w (2 − η + ε) and Δt w (η + ε).
  EXPECT_NEAR(lambda[0] + lambda[1], sum / (kDt_s * w * (2.0 - eta + epsilon)),
              1e-9 * sum / (kDt_s * w));
  EXPECT_NEAR(lambda[0] - lambda[1], difference / (kDt_s * w * (eta + epsilon)),
              1e-6 * std::abs(difference) / (kDt_s * w * epsilon));
  EXPECT_GT(lambda.minCoeff(), 0.0);  // both push, as the one row they nearly are would

  options.equality_compliance = 0.0;  // the exact solve: the same pair pulled apart
  SolveContactImpulses(W, rhs, kDt_s, 1, options, &lambda);
  EXPECT_LT(lambda.minCoeff(), -100.0 * (lambda[0] + lambda[1]));
}

// Exact LCP solution by trying every active set: λ_A = (ΔtW_AA)⁻¹ rhs_A, λ_rest = 0, and keep the
// one with λ ≥ 0 and c = ΔtWλ − rhs ≥ 0.
Eigen::VectorXd SolveLcpByEnumeration(const Eigen::MatrixXd& W, const Eigen::VectorXd& rhs) {
  const int n = static_cast<int>(rhs.size());
  for (int mask = 0; mask < (1 << n); ++mask) {
    std::vector<int> active;
    for (int i = 0; i < n; ++i)
      if (mask & (1 << i)) active.push_back(i);
    Eigen::VectorXd lambda = Eigen::VectorXd::Zero(n);
    if (!active.empty()) {
      Eigen::MatrixXd W_aa(active.size(), active.size());
      Eigen::VectorXd r_a(active.size());
      for (size_t i = 0; i < active.size(); ++i) {
        r_a[i] = rhs[active[i]];
        for (size_t j = 0; j < active.size(); ++j) W_aa(i, j) = kDt_s * W(active[i], active[j]);
      }
      const Eigen::VectorXd l_a = W_aa.lu().solve(r_a);
      for (size_t i = 0; i < active.size(); ++i) lambda[active[i]] = l_a[i];
    }
    const Eigen::VectorXd c = kDt_s * W * lambda - rhs;
    if (lambda.minCoeff() >= -1e-12 && c.minCoeff() >= -1e-12 * rhs.norm()) return lambda;
  }
  ADD_FAILURE() << "no active set solves the LCP";
  return Eigen::VectorXd::Zero(n);
}

TEST(ContactResponse, ProjectedGaussSeidelMatchesEnumeratedLcp) {
  for (unsigned seed = 2; seed < 12; ++seed) {
    Problem p = MakeProblem(6, seed);
    // Mixed signs so that some contacts separate: the active set is not all of them.
    for (int i = 0; i < 6; i += 2) p.b[i] -= 5.0;
    const Assembled a = Assemble(p, 1);
    const Eigen::VectorXd rhs = p.b - a.c_free;
    Eigen::VectorXd lambda;
    ContactSolveOptions options{ContactLaw::kUnilateral};
    options.max_iterations = 20000;
    const ContactSolveReport report = SolveContactImpulses(a.W, rhs, kDt_s, 1, options, &lambda);
    EXPECT_TRUE(report.converged) << "seed " << seed << " residual " << report.residual;
    const Eigen::VectorXd exact = SolveLcpByEnumeration(a.W, rhs);
    EXPECT_LT((lambda - exact).norm(), 1e-8 * std::max(1.0, exact.norm())) << "seed " << seed;
  }
}

// The active-set solve's bordered LU (contact_solver.cc, FreeSet) on W that is not symmetric,
// as with a rotating tool: W = SPD + a skew part, so the rows and the columns of a border differ
// (l ≠ u). Mixed targets make rows enter and then leave the free set; a duplicated row (the same
// constraint twice) makes a pivot vanish, which must switch that solve to pivoted LU. Against the
// enumerated LCP, whose solution is unique (W's symmetric part is positive definite).
TEST(ContactResponse, ActiveSetMatchesEnumeratedLcpOnAnUnsymmetricW) {
  std::mt19937 rng(17);
  std::normal_distribution<double> normal(0.0, 1.0);
  int left_rows = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 9;
    Eigen::MatrixXd B(n, n), S(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) B(i, j) = normal(rng), S(i, j) = normal(rng);
    Eigen::MatrixXd W =
        B * B.transpose() / n + 0.05 * Eigen::MatrixXd::Identity(n, n) + 0.5 * (S - S.transpose());
    Eigen::VectorXd rhs(n);
    for (int i = 0; i < n; ++i) rhs[i] = 1e-3 * normal(rng);
    if (trial % 4 == 3) {  // row 1 repeats row 0: a singular pair, kept apart by the shift only
      W.row(1) = W.row(0);
      W.col(1) = W.col(0);
      rhs[1] = rhs[0];
    }
    Eigen::VectorXd lambda;
    const ContactSolveReport report = SolveContactImpulses(
        W, rhs, kDt_s, 1, ContactSolveOptions{ContactLaw::kUnilateral}, &lambda);
    EXPECT_TRUE(report.converged) << "trial " << trial << " residual " << report.residual;
    // The solver's λ meets the LCP's conditions on W itself (λ ≥ 0, c ≥ 0, cᵀλ = 0)...
    const Eigen::VectorXd c = kDt_s * W * lambda - rhs;
    const double scale = rhs.lpNorm<Eigen::Infinity>();
    EXPECT_GE(lambda.minCoeff(), 0.0) << trial;
    EXPECT_GE(c.minCoeff(), -1e-8 * scale) << trial;
    EXPECT_LE(std::abs(c.dot(lambda)), 1e-8 * scale * lambda.lpNorm<1>()) << trial;
    // ...and, where the solution is unique (no duplicated row), equals the enumerated one.
    if (trial % 4 != 3) {
      const Eigen::VectorXd exact = SolveLcpByEnumeration(W, rhs);
      EXPECT_LT((lambda - exact).norm(), 1e-7 * std::max(1e-9, exact.norm())) << trial;
    }
    left_rows += report.iterations - (lambda.array() > 0.0).count();
  }
  // Rows that entered and later left: the rebuild path ran.
  EXPECT_GT(left_rows, 0);
}

// The active-set solve started from a λ (the last frame's, contact/impulse_warm_start.h): from the
// solution's own rows it needs no entering row; from a start with wrong rows (rows the solution
// leaves at zero, rows missing, negative entries, wild magnitudes) it still ends at the enumerated
// solution. Fails if the start's rows were kept without the equality solve and the ratio test.
TEST(ContactResponse, ActiveSetFromAnyStartEndsAtTheEnumeratedLcp) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int wrong_starts = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 10;
    Eigen::MatrixXd B(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) B(i, j) = normal(rng);
    const Eigen::MatrixXd W = B * B.transpose() / n + 0.05 * Eigen::MatrixXd::Identity(n, n);
    Eigen::VectorXd rhs(n);
    for (int i = 0; i < n; ++i) rhs[i] = 1e-3 * normal(rng);
    const Eigen::VectorXd exact = SolveLcpByEnumeration(W, rhs);
    const double tolerance = 1e-7 * std::max(1e-9, exact.norm());

    Eigen::VectorXd from_solution = exact;
    const ContactSolveOptions options{ContactLaw::kUnilateral};
    const ContactSolveReport settled =
        SolveContactImpulses(W, rhs, kDt_s, 1, options, &from_solution);
    EXPECT_EQ(settled.iterations, 0) << trial;
    EXPECT_LT((from_solution - exact).norm(), tolerance) << trial;

    Eigen::VectorXd start(n);
    for (int i = 0; i < n; ++i)
      start[i] = uniform(rng) < 0.5 ? 0.0 : 10.0 * normal(rng) * exact.norm();
    wrong_starts += ((start.array() > 0.0) != (exact.array() > 0.0)).any();
    Eigen::VectorXd lambda = start;
    const ContactSolveReport report = SolveContactImpulses(W, rhs, kDt_s, 1, options, &lambda);
    EXPECT_TRUE(report.converged) << trial;
    EXPECT_LT((lambda - exact).norm(), tolerance) << trial;
  }
  EXPECT_GT(wrong_starts, 30);
}

// A start with many loaded rows is factored by blocks of 16 (the free set's AddAll), not row by
// row as entering rows are: started from the solution of a cold solve on a 60-row unsymmetric W
// with ~40 rows loaded, it needs no entering row and returns that solution; the complementarity
// conditions are checked directly. With a row duplicated in the start (a zero pivot), the blocked
// factor fails as bordering would, and the solve still ends at a solution of the LCP.
TEST(ContactResponse, ActiveSetStartedWithManyRowsEndsWhereTheColdSolveDoes) {
  std::mt19937 rng(31);
  std::normal_distribution<double> normal(0.0, 1.0);
  const ContactSolveOptions options{ContactLaw::kUnilateral};
  for (int trial = 0; trial < 10; ++trial) {
    const int n = 60;
    Eigen::MatrixXd B(n, n), S(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) B(i, j) = normal(rng), S(i, j) = normal(rng);
    Eigen::MatrixXd W =
        B * B.transpose() / n + 0.05 * Eigen::MatrixXd::Identity(n, n) + 0.1 * (S - S.transpose());
    const bool duplicated = trial % 2 == 1;
    if (duplicated) {  // row and column 1 repeat row and column 0
      W.row(1) = W.row(0);
      W.col(1) = W.col(0);
    }
    Eigen::VectorXd rhs(n);
    for (int i = 0; i < n; ++i) rhs[i] = 1e-3 * (normal(rng) + 1.5);  // most rows loaded
    if (duplicated) rhs[1] = rhs[0];
    Eigen::VectorXd cold = Eigen::VectorXd::Zero(n);
    ASSERT_TRUE(SolveContactImpulses(W, rhs, kDt_s, 1, options, &cold).converged) << trial;
    Eigen::VectorXd warm = cold;
    if (duplicated) warm[1] = warm[0] = 0.5 * (cold[0] + cold[1]) + 1e-3;  // both rows loaded
    ASSERT_GT((warm.array() > 0.0).count(), 32) << trial;                  // two blocks and more
    const ContactSolveReport report = SolveContactImpulses(W, rhs, kDt_s, 1, options, &warm);
    EXPECT_TRUE(report.converged) << trial;
    // The slack, to within the solver's 1e-10 relative shift of W's diagonal.
    const Eigen::VectorXd w = kDt_s * W * warm - rhs;
    const double scale = rhs.lpNorm<Eigen::Infinity>();
    EXPECT_GE(warm.minCoeff(), 0.0) << trial;
    EXPECT_GT(w.minCoeff(), -1e-8 * scale) << trial;
    EXPECT_LT(std::abs(warm.dot(w)), 1e-8 * scale * warm.lpNorm<1>()) << trial;
    if (!duplicated) {
      EXPECT_EQ(report.iterations, 0) << trial;
      EXPECT_LT((warm - cold).norm(), 1e-9 * cold.norm()) << trial;
    }
  }
}

// The unilateral solve reading W by columns (SolveUnilateralByColumns, as the visual frame calls
// it) gives the dense solve's λ bit for bit, on unsymmetric W from good and wrong starts, while
// asking for fewer columns than W has: the W it reads holds NaN in every column not asked for, so
// a read of one would show in λ. Every row left with λ ≠ 0 was asked for (a row that leaves and
// enters again is asked for again: the caller keeps what it has filled).
TEST(ContactResponse, UnilateralByColumnsReadsOnlyTheColumnsItAsksFor) {
  std::mt19937 rng(23);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int columns_asked = 0, columns_whole = 0;
  for (int trial = 0; trial < 30; ++trial) {
    const int n = 40;
    Eigen::MatrixXd B(n, n), S(n, n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) B(i, j) = normal(rng), S(i, j) = normal(rng);
    const Eigen::MatrixXd W =
        B * B.transpose() / n + 0.05 * Eigen::MatrixXd::Identity(n, n) + 0.3 * (S - S.transpose());
    Eigen::VectorXd rhs(n);
    for (int i = 0; i < n; ++i) rhs[i] = 1e-3 * (normal(rng) - 0.8);  // most rows idle
    Eigen::VectorXd start = Eigen::VectorXd::Zero(n);
    if (trial % 2 == 1)  // a wrong start: some rows loaded that the solution leaves idle
      for (int i = 0; i < n; ++i) start[i] = uniform(rng) < 0.2 ? std::abs(normal(rng)) : 0.0;
    const ContactSolveOptions options{ContactLaw::kUnilateral};
    Eigen::VectorXd dense = start;
    const ContactSolveReport dense_report = SolveContactImpulses(W, rhs, kDt_s, 1, options, &dense);

    Eigen::MatrixXd W_part = Eigen::MatrixXd::Constant(n, n, std::nan(""));
    std::vector<int> times_asked(n, 0);
    const ColumnFiller fill = [&](const std::vector<Eigen::Index>& columns) {
      for (Eigen::Index c : columns) {
        W_part.col(c) = W.col(c);
        ++times_asked[static_cast<size_t>(c)];
      }
    };
    Eigen::VectorXd by_columns = start;
    const ContactSolveReport report =
        SolveUnilateralByColumns(W_part, W.diagonal(), fill, rhs, kDt_s, options, &by_columns);
    EXPECT_TRUE(dense_report.converged) << trial;
    EXPECT_TRUE(report.converged) << trial;
    EXPECT_EQ(report.iterations, dense_report.iterations) << trial;
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(by_columns[i], dense[i]) << trial << ", row " << i;
      if (by_columns[i] != 0.0) {
        EXPECT_GE(times_asked[static_cast<size_t>(i)], 1) << trial;
      }
    }
    columns_asked += static_cast<int>(n - std::count(times_asked.begin(), times_asked.end(), 0));
    columns_whole += n;
  }
  EXPECT_LT(columns_asked, columns_whole / 2);  // the point of it: most columns never formed
}

TEST(ContactResponse, CoulombFrictionSticksInsideTheConeAndSlidesOnIt) {
  // One contact whose rows are decoupled (W diagonal): the closed form is λ_n = rhs_n/(ΔtW_nn),
  // λ_t = rhs_t/(ΔtW_tt) if |λ_t| ≤ μλ_n (stick), else μλ_n along it (slide).
  const Eigen::Matrix3d W = Eigen::Vector3d(2.0, 3.0, 3.0).asDiagonal();
  const double mu = 0.5;
  ContactSolveOptions options{ContactLaw::kFriction, mu};
  for (const double tangential : {0.3e-3, 3e-3}) {  // stick, then slide
    const Eigen::Vector3d rhs(4e-3, tangential, -0.5 * tangential);
    Eigen::VectorXd lambda;
    SolveContactImpulses(W, rhs, kDt_s, 3, options, &lambda);
    const double normal = rhs[0] / (kDt_s * W(0, 0));
    const Eigen::Vector2d stick = rhs.tail<2>() / (kDt_s * 3.0);
    const Eigen::Vector2d expected =
        stick.norm() <= mu * normal ? stick : (mu * normal) * stick.normalized();
    EXPECT_NEAR(lambda[0], normal, 1e-12 * normal);
    EXPECT_LT((lambda.tail<2>() - expected).norm(), 1e-12 * normal);
  }
}

TEST(LinearContactModel, ReproducesTheEqualitySolveAtAndAwayFromItsLinearisation) {
  const Problem p = MakeProblem(7, 21);
  const Assembled a = Assemble(p, 1);
  const Eigen::MatrixXd J_u = Eigen::MatrixXd(a.J.J_u);
  const Eigen::VectorXd u_free = p.u_dot_m_s + p.A_u.ldlt().solve(p.body_force_dt);
  // The law the frame solves and its model holds: the equality law with its compliance
  // (contact/visual_frame_model.cc builds the model so).
  const ContactSolveOptions law{ContactLaw::kEquality};
  Eigen::MatrixXd W_law = a.W;
  AddEqualityCompliance(law.equality_compliance, &W_law);
  const LinearContactModel model = MakeLinearContactModel(a.J, W_law, p.tool, p.b - J_u * u_free);
  Eigen::Vector3d F_hat, T_hat;
  CalcDiscreteTimeWrench(p.tool, p.tool_state, &F_hat, &T_hat);
  // Perturb F̂, T̂ as the user's motion would between visual frames.
  for (const double scale : {0.0, 1.0, 10.0}) {
    const Eigen::Vector3d dF = scale * Eigen::Vector3d(0.5, -1.0, 2.0);
    const Eigen::Vector3d dT = scale * Eigen::Vector3d(-0.01, 0.02, 0.005);
    ToolStepSystem tool = p.tool;
    tool.F_tilde_N += dF;
    tool.T_tilde_N_m += dT;
    // Full re-solve with the perturbed free velocities.
    const Eigen::Vector3d v_free = tool.A_v.inverse() * kDt_s * (F_hat + dF);
    const Eigen::Vector3d w_free = tool.M_inv_W * tool.A_L.inverse() * kDt_s * (T_hat + dT);
    const Eigen::VectorXd c_free = a.J.J_v * v_free + a.J.J_w * w_free + J_u * u_free;
    Eigen::VectorXd lambda;
    SolveContactImpulses(a.W, p.b - c_free, kDt_s, 1, law, &lambda);
    const Eigen::Vector3d F_solve = a.J.J_v.transpose() * lambda;
    const Eigen::Vector3d T_solve = a.J.J_w.transpose() * lambda;
    Eigen::Vector3d F_model, T_model;
    EvaluateLinearContactModel(model, F_hat + dF, T_hat + dT, &F_model, &T_model);
    EXPECT_LT((F_model - F_solve).norm(), 1e-9 * F_solve.norm()) << "scale " << scale;
    EXPECT_LT((T_model - T_solve).norm(), 1e-9 * T_solve.norm()) << "scale " << scale;
  }
}

}  // namespace
}  // namespace hapsim::contact
