// Google Benchmark: the haptic step's contact solves (DESIGN.md §4) at n = 25, 50, 125 rows.
// Not a test: run `build/tests/haptic_lcp_benchmark`.
//
//  BM_HapticLcpWarm       HapticLcpSolver::Solve at a haptic step within a visual frame: same
//                         rows, F̂ perturbed slightly every call (warm start, no factorisation)
//  BM_HapticLcpNewRows    the first haptic step of a visual frame: the rows alternate between
//                         two frames, so every call copies the rows and factorises a base block;
//                         rows:2 the frame's active contacts (realistic), rows:0 rows of which
//                         ~20% separate at once (a poor first guess: two factorisations)
//  BM_DenseLu             one dense partial-pivoting LU of W (n × n): the floor of the plain
//                         warm-started active-set method, which refactorises W_AA at every step
//                         because the tool part of W changes at every step
//  BM_ReferenceActiveSet  SolveContactImpulses(kUnilateral) from a cold start
//  BM_EvaluateLinearContactModel  the paper's fast path (four 3×3 products)
//
// Problems as in tests/contact/haptic_lcp_test.cc: n contacts of a tool pressing on a body of
// n + 1 nodes with a random SPD matrix, soft enough and pressed enough that most contacts are
// active (the rows the visual frame hands over are mostly ones it found active); ~15% separate.

#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

#include "contact/contact_jacobian.h"
#include "contact/contact_solver.h"
#include "contact/haptic_lcp_solver.h"
#include "contact/linear_contact_model.h"

namespace hapsim::contact {
namespace {

constexpr double kDt_s = 1e-3;

struct Problem {
  ContactJacobian J;
  ContactRows rows;
  ToolStepSystem tool;
  Eigen::MatrixXd W;  // tool part + W_body
  Eigen::Vector3d F_hat_N, T_hat_N_m;
};

Problem MakeProblem(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto random3 = [&] { return Eigen::Vector3d(unit(rng), unit(rng), unit(rng)); };
  Problem p;
  p.tool.dt_s = kDt_s;
  p.tool.A_v = (0.05 + kDt_s * 2.0 + kDt_s * kDt_s * 2000.0) * Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d inertia = Eigen::Vector3d(2e-5, 3e-5, 1e-5).asDiagonal();
  p.tool.M_inv_W = inertia.inverse();
  Eigen::Matrix3d skew;
  skew << 0, -1, 0.5, 1, 0, -2, -0.5, 2, 0;
  const Eigen::Matrix3d C =
      (kDt_s * 0.01 + kDt_s * kDt_s) * Eigen::Matrix3d::Identity() + 0.3 * kDt_s * kDt_s * skew;
  p.tool.A_L = Eigen::Matrix3d::Identity() + C * p.tool.M_inv_W;
  const int num_dofs = 3 * (n + 1);
  const Eigen::Vector3d x_tool(0.0, 0.0, 0.02);
  std::vector<Contact> contacts(n);
  for (int i = 0; i < n; ++i) {
    contacts[i].n_W = (random3() + Eigen::Vector3d(0, 0, -2.0)).normalized();
    contacts[i].p_tool_W_m = x_tool + 0.01 * random3();
    const double w = 0.5 + 0.4 * unit(rng);
    contacts[i].SetBodyNodes({i, i + 1}, {w, 1.0 - w});
  }
  p.J = CalcContactJacobian(contacts, x_tool, 1, num_dofs, std::vector<std::uint8_t>(num_dofs, 0));
  const Eigen::MatrixXd R =
      Eigen::MatrixXd::NullaryExpr(num_dofs, num_dofs, [&] { return unit(rng); });
  const Eigen::MatrixXd A_u =
      R * R.transpose() * 1e-3 + 1e-2 * Eigen::MatrixXd::Identity(num_dofs, num_dofs);
  const Eigen::MatrixXd J_u = Eigen::MatrixXd(p.J.J_u);
  // A soft body (compliance ×100) pressed by the tool: most contacts carry load.
  const Eigen::MatrixXd W_body = 100.0 * J_u * A_u.ldlt().solve(J_u.transpose());
  Eigen::VectorXd body_rhs(n);
  for (int i = 0; i < n; ++i) body_rhs[i] = 0.1 * unit(rng) + 1.0;
  p.rows = MakeContactRows(p.J, W_body, body_rhs);
  p.W = CalcToolDelassus(p.J, p.tool) + p.rows.W_body;
  p.F_hat_N = Eigen::Vector3d(0.3, -0.2, -3.0) + 0.05 * random3();
  p.T_hat_N_m = Eigen::Vector3d(0.01, 0.02, -0.005);
  return p;
}

// The rows a visual frame hands over when it sends its active contacts: a problem with more
// contacts is solved and its first n active rows are kept (most stay active, a few separate as
// the others' load shifts).
Problem MakeFrameProblem(int n, unsigned seed) {
  for (int m = n;; m += std::max(1, n / 10)) {
    const Problem full = MakeProblem(m, seed);
    HapticLcpSolver solver(m);
    Eigen::Vector3d F_c, T_c;
    solver.Solve(full.rows, full.tool, full.F_hat_N, full.T_hat_N_m, &F_c, &T_c);
    std::vector<int> rows;
    for (int i = 0; i < m && static_cast<int>(rows.size()) < n; ++i)
      if (solver.last_impulses()[i] > 0.0) rows.push_back(i);
    if (static_cast<int>(rows.size()) < n) continue;
    Problem p = full;
    p.J = ContactJacobian{};
    p.J.J_v.resize(n, 3);
    p.J.J_w.resize(n, 3);
    Eigen::VectorXd body_rhs(n);
    for (int a = 0; a < n; ++a) {
      p.J.J_v.row(a) = full.rows.J_v.row(rows[a]);
      p.J.J_w.row(a) = full.rows.J_w.row(rows[a]);
      body_rhs[a] = full.rows.body_rhs[rows[a]];
    }
    p.rows = MakeContactRows(p.J, full.rows.W_body, rows, body_rhs);
    p.W = CalcToolDelassus(p.J, p.tool) + p.rows.W_body;
    return p;
  }
}

// which 0, 1: two frames of MakeProblem; 2, 3: two frames of MakeFrameProblem.
const Problem& GetProblem(int n, int which) {
  static std::vector<std::pair<std::pair<int, int>, Problem*>> cache;
  for (const auto& [key, problem] : cache)
    if (key == std::make_pair(n, which)) return *problem;
  const unsigned seed = 1000 * n + which;
  cache.push_back(
      {{n, which}, new Problem(which < 2 ? MakeProblem(n, seed) : MakeFrameProblem(n, seed))});
  return *cache.back().second;
}

void SetCounters(benchmark::State& bench, const HapticLcpSolver& solver) {
  bench.counters["rows"] = solver.last_impulses().size();
  bench.counters["active"] = solver.last_num_active();
  bench.counters["solves"] = solver.last_iterations();
  bench.counters["factorisations"] = solver.last_num_factorizations();
}

void BM_HapticLcpWarm(benchmark::State& bench) {
  const int n = static_cast<int>(bench.range(0));
  const Problem& p = GetProblem(n, 0);
  HapticLcpSolver solver(150);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::Vector3d F_c, T_c, F_hat = p.F_hat_N;
  solver.Solve(p.rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c);  // the frame's first step
  for (auto _ : bench) {
    F_hat = p.F_hat_N + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    if (!solver.Solve(p.rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c))
      bench.SkipWithError("solve failed");
    benchmark::DoNotOptimize(F_c.data());
  }
  SetCounters(bench, solver);
}

// range(1): 0 = rows of MakeProblem (~20% of them separate), 2 = the frame's active rows.
void BM_HapticLcpNewRows(benchmark::State& bench) {
  const int n = static_cast<int>(bench.range(0));
  const int kind = static_cast<int>(bench.range(1));
  const Problem* frames[2] = {&GetProblem(n, kind), &GetProblem(n, kind + 1)};
  HapticLcpSolver solver(150);
  Eigen::Vector3d F_c, T_c;
  int k = 0;
  for (auto _ : bench) {
    const Problem& p = *frames[k++ % 2];
    if (!solver.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_c, &T_c))
      bench.SkipWithError("solve failed");
    benchmark::DoNotOptimize(F_c.data());
  }
  SetCounters(bench, solver);
}

void BM_DenseLu(benchmark::State& bench) {
  const Problem& p = GetProblem(static_cast<int>(bench.range(0)), 0);
  Eigen::PartialPivLU<Eigen::MatrixXd> lu(p.W.rows());
  for (auto _ : bench) {
    lu.compute(p.W);
    benchmark::DoNotOptimize(lu.matrixLU().data());
  }
}

void BM_ReferenceActiveSet(benchmark::State& bench) {
  const Problem& p = GetProblem(static_cast<int>(bench.range(0)), 0);
  const Eigen::Vector3d v_free = p.tool.A_v.inverse() * kDt_s * p.F_hat_N;
  const Eigen::Vector3d w_free = p.tool.M_inv_W * p.tool.A_L.inverse() * kDt_s * p.T_hat_N_m;
  const Eigen::VectorXd rhs = p.rows.body_rhs - p.rows.J_v * v_free - p.rows.J_w * w_free;
  Eigen::VectorXd lambda;
  ContactSolveReport report;
  for (auto _ : bench) {
    lambda.setZero();
    report = SolveContactImpulses(p.W, rhs, kDt_s, 1, ContactSolveOptions{ContactLaw::kUnilateral},
                                  &lambda);
    benchmark::DoNotOptimize(lambda.data());
  }
  bench.counters["active"] = static_cast<double>((lambda.array() > 0.0).count());
  bench.counters["iterations"] = report.iterations;
}

void BM_EvaluateLinearContactModel(benchmark::State& bench) {
  const Problem& p = GetProblem(static_cast<int>(bench.range(0)), 0);
  const LinearContactModel model = MakeLinearContactModel(p.J, p.W, p.tool, p.rows.body_rhs);
  Eigen::Vector3d F_c, T_c, F_hat = p.F_hat_N;
  for (auto _ : bench) {
    F_hat.x() += 1e-9;
    EvaluateLinearContactModel(model, F_hat, p.T_hat_N_m, &F_c, &T_c);
    benchmark::DoNotOptimize(F_c.data());
  }
}

BENCHMARK(BM_HapticLcpWarm)->Arg(25)->Arg(50)->Arg(125)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HapticLcpNewRows)
    ->ArgsProduct({{25, 50, 125}, {2, 0}})
    ->ArgNames({"n", "rows"})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_DenseLu)->Arg(25)->Arg(50)->Arg(125)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ReferenceActiveSet)->Arg(25)->Arg(50)->Arg(125)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_EvaluateLinearContactModel)->Arg(125)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hapsim::contact

BENCHMARK_MAIN();
