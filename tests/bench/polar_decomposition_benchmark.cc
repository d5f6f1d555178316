// Google Benchmark: the rotation of the deformation gradient, one element at a time
// (CalcRotationOfDeformation) against kPolarBatchLanes at a time (CalcRotationsOfDeformation, its
// AVX2 clone on a CPU that has AVX2). Not a test: run `build/tests/polar_decomposition_benchmark`
// from the repository root (it reads scenes/). Only the rotation calls are timed; the F's are
// computed once:
//   set 0, 1: every tet's F in the 3,600- and 28,800-tet blocks after 30 steps from rest (as
//             fem_step_benchmark's fixture): small strains, |det X − 1| < 1e-3 so γ = 1, and
//             3 Newton iterations for 97% of the tets, 2 for the rest;
//   set 2:    3,600 strained F = Q Vᵀ diag(s) V, s uniform in [0.7, 1.3], Q and V random
//             rotations: the first iterations need the scaling γ = ∛(1/det X) (~2 per tet),
//             and 3-4 Newton iterations.
// The counter per_tet is the time of one call divided by the number of F's.

#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "config/body_builder.h"
#include "config/scene.h"
#include "fem/polar_decomposition.h"
#include "fem/time_stepper.h"

namespace hapsim {
namespace {

const char* kScenes[] = {"scenes/block_small.yaml", "scenes/block_large.yaml"};
constexpr int kWarmUpSteps = 30;
constexpr int kNumStrained = 3600;

std::vector<Eigen::Matrix3d> MakeBlockDeformationGradients(const char* scene_path) {
  const config::Scene scene = config::LoadScene(scene_path);
  const config::Body body = config::MakeBody(*scene.body, scene.gravity_m_s2);
  const fem::Model& model = body.model;
  fem::State state = fem::MakeRestState(model);
  fem::TimeStepper stepper(model, scene.body->options, scene.dt_s, body.external_force_N);
  for (int k = 0; k < kWarmUpSteps; ++k) stepper.Step(&state);
  // F = Σ_a x_a b_aᵀ, as fem/corotational.cc computes it.
  std::vector<Eigen::Matrix3d> F(model.num_tets());
  for (int t = 0; t < model.num_tets(); ++t) {
    Eigen::Matrix<double, 3, 4> x_local_m;
    for (int a = 0; a < 4; ++a) x_local_m.col(a) = state.x_m.segment<3>(3 * model.mesh.tets(a, t));
    F[t] = x_local_m * model.tet_rest[t].shape_gradients_1_m.transpose();
  }
  return F;
}

Eigen::Matrix3d RandomRotation(std::mt19937* engine) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(*engine), normal(*engine), normal(*engine), normal(*engine));
  return q.normalized().toRotationMatrix();  // uniform on SO(3)
}

std::vector<Eigen::Matrix3d> MakeStrainedDeformationGradients() {
  std::mt19937 engine(7);
  std::uniform_real_distribution<double> stretch(0.7, 1.3);
  std::vector<Eigen::Matrix3d> F(kNumStrained);
  for (Eigen::Matrix3d& f : F) {
    const Eigen::Matrix3d V = RandomRotation(&engine);
    const Eigen::Vector3d s(stretch(engine), stretch(engine), stretch(engine));
    f = RandomRotation(&engine) * V.transpose() * s.asDiagonal() * V;
  }
  return F;
}

// Built once per set and kept: stepping the large block is not what is measured.
const std::vector<Eigen::Matrix3d>& GetDeformationGradients(int set) {
  static std::vector<Eigen::Matrix3d>* sets[3] = {};
  if (!sets[set]) {
    sets[set] = new std::vector<Eigen::Matrix3d>(
        set < 2 ? MakeBlockDeformationGradients(kScenes[set]) : MakeStrainedDeformationGradients());
  }
  return *sets[set];
}

void SetCounters(benchmark::State& bench, int count) {
  bench.counters["tets"] = count;
  // An inverted rate: seconds per F (printed with its SI prefix, e.g. 21.4n).
  bench.counters["per_tet"] = benchmark::Counter(
      count, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void BM_Scalar(benchmark::State& bench) {
  const std::vector<Eigen::Matrix3d>& F = GetDeformationGradients(static_cast<int>(bench.range(0)));
  std::vector<Eigen::Matrix3d> R(F.size());
  for (auto _ : bench) {
    for (size_t i = 0; i < F.size(); ++i) R[i] = fem::CalcRotationOfDeformation(F[i]);
    benchmark::DoNotOptimize(R.data());
    benchmark::ClobberMemory();
  }
  SetCounters(bench, static_cast<int>(F.size()));
}

void BM_Batched(benchmark::State& bench) {
  const std::vector<Eigen::Matrix3d>& F = GetDeformationGradients(static_cast<int>(bench.range(0)));
  std::vector<Eigen::Matrix3d> R(F.size());
  for (auto _ : bench) {
    fem::CalcRotationsOfDeformation(F.data(), static_cast<int>(F.size()), R.data());
    benchmark::DoNotOptimize(R.data());
    benchmark::ClobberMemory();
  }
  SetCounters(bench, static_cast<int>(F.size()));
}

BENCHMARK(BM_Scalar)->DenseRange(0, 2)->ArgName("set")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Batched)->DenseRange(0, 2)->ArgName("set")->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hapsim

BENCHMARK_MAIN();
