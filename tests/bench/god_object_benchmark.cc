// GodObject::Step (contact/god_object.h) against triangle count: a bumpy height field of 1k,
// 10k and 100k triangles (2 n² for n = 22, 71, 224 cells a side) with the HIP sliding round a
// circle 2 mm under the surface (one or two active planes, a new triangle every few steps), and
// the HIP in free space above it. Friction and shading on.
//
//   build/tests/god_object_benchmark --benchmark_repetitions=5 --benchmark_report_aggregates_only

#include <benchmark/benchmark.h>

#include <cmath>

#include "contact/god_object.h"

namespace hapsim::contact {
namespace {

TriangleMesh MakeBumpyField(int n) {
  const double size_m = 0.2;
  TriangleMesh mesh;
  mesh.vertices_m.resize(3, (n + 1) * (n + 1));
  mesh.triangles.resize(3, 2 * n * n);
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const double x = size_m * (i / static_cast<double>(n) - 0.5);
      const double y = size_m * (j / static_cast<double>(n) - 0.5);
      mesh.vertices_m.col(j * (n + 1) + i) << x, y, 3e-3 * std::sin(60 * x) * std::sin(60 * y);
    }
  }
  for (int j = 0, f = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      mesh.triangles.col(f++) << a, a + 1, a + n + 2;
      mesh.triangles.col(f++) << a, a + n + 2, a + n + 1;
    }
  }
  return mesh;
}

void Run(benchmark::State& state, bool contact) {
  GodObjectParams params;
  params.stiffness_N_m = 1000.0;
  params.proxy_radius_m = 0.5e-3;
  params.static_friction = 0.3;
  params.dynamic_friction = 0.2;
  params.shading = true;
  GodObject god(params);
  god.AddMesh(MakeBumpyField(static_cast<int>(state.range(0))), Eigen::Isometry3d::Identity());
  const double depth_m = contact ? -2e-3 : 0.02;
  god.Reset(Eigen::Vector3d(0.05, 0.0, 0.02));
  int i = 0;
  int contacts = 0;
  for (auto _ : state) {
    // 1 m/s round a 5 cm circle at 1 kHz: 1 mm a step.
    const double a = 0.02 * i++;
    god.Step(Eigen::Vector3d(0.05 * std::cos(a), 0.05 * std::sin(a), depth_m));
    contacts += god.in_contact();
    benchmark::DoNotOptimize(god.force_W_N());
  }
  state.counters["triangles"] = 2.0 * state.range(0) * state.range(0);
  state.counters["contact_fraction"] = contacts / static_cast<double>(i);
}

void BM_StepSliding(benchmark::State& state) { Run(state, true); }
void BM_StepFreeSpace(benchmark::State& state) { Run(state, false); }

BENCHMARK(BM_StepSliding)->Arg(22)->Arg(71)->Arg(224)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_StepFreeSpace)->Arg(22)->Arg(71)->Arg(224)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hapsim::contact

BENCHMARK_MAIN();
