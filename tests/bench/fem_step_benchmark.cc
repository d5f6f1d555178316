// Google Benchmark: the stages of one implicit FEM step on the reference blocks (DESIGN.md §7).
// Not a test: run `build/tests/fem_step_benchmark` from the repository root (it reads scenes/).
// The state is first advanced 30 steps from rest so rotations and CG warm starts are realistic.

#include <benchmark/benchmark.h>

#include "config/body_builder.h"
#include "config/scene.h"
#include "fem/corotational.h"
#include "fem/stiffness_assembly.h"
#include "fem/time_stepper.h"

namespace hapsim {
namespace {

const char* kScenes[] = {"scenes/block_tiny.yaml", "scenes/block_small.yaml",
                         "scenes/block_large.yaml"};
constexpr int kWarmUpSteps = 30;

struct Fixture {
  config::Scene scene;
  config::Body body;
  fem::State state;
};

// Built once per scene and kept: meshing the large block is not what is measured.
const Fixture& GetFixture(int index) {
  static Fixture* fixtures[3] = {};
  if (!fixtures[index]) {
    auto* f = new Fixture{config::LoadScene(kScenes[index]), {}, {}};
    f->body = config::MakeBody(*f->scene.body, f->scene.gravity_m_s2);
    f->state = fem::MakeRestState(f->body.model);
    fem::TimeStepper stepper(f->body.model, f->scene.body->options, f->scene.dt_s,
                             f->body.external_force_N);
    for (int k = 0; k < kWarmUpSteps; ++k) stepper.Step(&f->state);
    fixtures[index] = f;
  }
  return *fixtures[index];
}

void SetCounters(benchmark::State& bench, const Fixture& f) {
  bench.counters["tets"] = f.body.model.num_tets();
  bench.counters["dofs"] = f.body.model.num_dofs();
}

void BM_Rotations(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  std::vector<Eigen::Matrix3d> rotations;
  for (auto _ : bench) {
    fem::CalcElementRotations(f.body.model, f.state.x_m, fem::ElasticityKind::kCorotational,
                              &rotations);
    benchmark::DoNotOptimize(rotations.data());
  }
  SetCounters(bench, f);
}

void BM_ForcesAndStiffness(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  std::vector<Eigen::Matrix3d> rotations;
  fem::CalcElementRotations(f.body.model, f.state.x_m, fem::ElasticityKind::kCorotational,
                            &rotations);
  const fem::StiffnessAssembler assembler(f.body.model);
  Eigen::SparseMatrix<double> K = assembler.MakeMatrix();
  Eigen::VectorXd force_N;
  for (auto _ : bench) {
    assembler.Assemble(f.body.model, rotations, &K);
    fem::CalcElasticForce(f.body.model, f.state.x_m, rotations, &force_N);
    benchmark::DoNotOptimize(K.valuePtr());
    benchmark::DoNotOptimize(force_N.data());
  }
  SetCounters(bench, f);
}

// A whole implicit step, continuing the motion (the state keeps evolving across iterations).
void BM_ImplicitStep(benchmark::State& bench) {
  const Fixture& f = GetFixture(static_cast<int>(bench.range(0)));
  fem::FemOptions options = f.scene.body->options;
  options.solver.kind =
      bench.range(1) == 0 ? fem::SolverKind::kConjugateGradient : fem::SolverKind::kCholmod;
  fem::TimeStepper stepper(f.body.model, options, f.scene.dt_s, f.body.external_force_N);
  fem::State state = f.state;
  stepper.Step(&state);  // first step: symbolic analysis and first factorisation
  double iterations = 0.0;
  for (auto _ : bench) iterations += stepper.Step(&state).solve.iterations;
  SetCounters(bench, f);
  bench.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}

BENCHMARK(BM_Rotations)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ForcesAndStiffness)->DenseRange(0, 2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ImplicitStep)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->ArgNames({"block", "cholmod"})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace hapsim

BENCHMARK_MAIN();
