// Google Benchmark: the haptic step's friction solve (contact/haptic_friction_solver.h), issue
// 13's target ≤ 100 µs per step at 200 contacts. Not a test: run
// `build/tests/haptic_friction_benchmark`.
//
//  BM_HapticFrictionWarm/m/sweeps   Solve at a haptic step within a visual frame: the same rows
//                                   (m contacts, 3m rows), F̂ moved by ~0.01 N every call (a user
//                                   at 1 kHz), warm from the previous step; at most `sweeps`
//                                   sweeps (the scene's budget). Counters: sweeps done, the
//                                   Coulomb residual left, contacts carrying load and sliding.
//  BM_HapticFrictionNewRows/m       the first step of a frame: rows alternate between two
//                                   frames, each started from its frame's impulses (as the
//                                   visual frame hands them over), so every call copies the
//                                   rows and forms W_body λ (O(n²)).
//
// Problems as in tests/contact/haptic_friction_test.cc (tests/contact/haptic_test_problems.h):
// a soft body pressed by the tool so that most contacts carry load, μ = 0.5.

#include <benchmark/benchmark.h>

#include <random>

#include "contact/haptic_friction_solver.h"
#include "tests/contact/haptic_test_problems.h"

namespace hapsim::contact {
namespace {

constexpr double kMu = 0.5;

const LcpProblem& GetProblem(int contacts, int which) {
  static std::vector<std::pair<std::pair<int, int>, LcpProblem*>> cache;
  for (const auto& [key, problem] : cache)
    if (key == std::make_pair(contacts, which)) return *problem;
  LcpProblem* p =
      new LcpProblem(MakeLcpProblem(contacts, 7000 + 10 * contacts + which, 1.0, 100.0, 3, kMu));
  // The frame's impulses: the converged solve at the frame's wrench.
  HapticFrictionSolver solver(3 * contacts, 100000);
  Eigen::Vector3d F_c, T_c;
  solver.Solve(p->rows, p->tool, p->F_hat_N, p->T_hat_N_m, &F_c, &T_c);
  p->rows.lambda_frame_N = solver.last_impulses();
  StampNewContactRows(&p->rows);  // as the visual frame's export and the LCM decode do
  cache.push_back({{contacts, which}, p});
  return *p;
}

void SetCounters(benchmark::State& bench, const HapticFrictionSolver& solver) {
  bench.counters["sweeps"] = solver.last_iterations();
  bench.counters["residual"] = solver.last_residual();
  bench.counters["active"] = solver.last_num_active();
  bench.counters["sliding"] = solver.last_num_sliding();
}

void BM_HapticFrictionWarm(benchmark::State& bench) {
  const int contacts = static_cast<int>(bench.range(0));
  const LcpProblem& p = GetProblem(contacts, 0);
  HapticFrictionSolver solver(3 * contacts, static_cast<int>(bench.range(1)));
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  Eigen::Vector3d F_c, T_c, F_hat = p.F_hat_N;
  solver.Solve(p.rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c);
  double sweeps = 0.0, residual = 0.0;
  for (auto _ : bench) {
    bench.PauseTiming();
    F_hat = p.F_hat_N + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    bench.ResumeTiming();
    solver.Solve(p.rows, p.tool, F_hat, p.T_hat_N_m, &F_c, &T_c);
    benchmark::DoNotOptimize(F_c);
    sweeps += solver.last_iterations();
    residual = std::max(residual, solver.last_residual());
  }
  SetCounters(bench, solver);
  bench.counters["sweeps"] = sweeps / static_cast<double>(bench.iterations());
  bench.counters["residual"] = residual;  // the worst step's
}
BENCHMARK(BM_HapticFrictionWarm)
    ->ArgsProduct({{25, 70, 200}, {1, 2, 5, 20, 1000}})
    ->Unit(benchmark::kMicrosecond);

void BM_HapticFrictionNewRows(benchmark::State& bench) {
  const int contacts = static_cast<int>(bench.range(0));
  const LcpProblem& a = GetProblem(contacts, 0);
  const LcpProblem& b = GetProblem(contacts, 1);
  HapticFrictionSolver solver(3 * contacts, 20);
  Eigen::Vector3d F_c, T_c;
  bool flip = false;
  for (auto _ : bench) {
    const LcpProblem& p = flip ? b : a;
    flip = !flip;
    solver.Solve(p.rows, p.tool, p.F_hat_N, p.T_hat_N_m, &F_c, &T_c);
    benchmark::DoNotOptimize(F_c);
  }
  SetCounters(bench, solver);
}
BENCHMARK(BM_HapticFrictionNewRows)->Arg(25)->Arg(70)->Arg(200)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hapsim::contact

BENCHMARK_MAIN();
