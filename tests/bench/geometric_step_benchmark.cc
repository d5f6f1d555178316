// Google Benchmark: one haptic step of the 1 kHz geometric modes
// (device/geometric_haptic_contact.h: penalty, material, impact) against contact count: a sphere
// tool (r 2 cm) held at depths of 0.25–8 mm in the rest block of scenes/block_press.yaml (4 mm top
// spacing; the body's surface as the frame would leave it, rigid between frames). Timed: the step's
// contact work (GeometricHapticContact::Calc: the search against the snapshot and the mode's
// force); the rest of the step (coupling, free tool, integration) is the linear mode's, ~0.4 µs
// (haptic_step_benchmark). Not a test: run
// `build/tests/geometric_step_benchmark` from the repository root (it reads scenes/).
//
//  BM_GeometricStep/mode:M/depth_um:D   M = 0 penalty, 1 material, 2 impact
//
// Counters: contacts (found by the step's search: within ε for penalty, touching for material,
// the search margin for impact).

#include <benchmark/benchmark.h>

#include <memory>

#include "config/body_builder.h"
#include "config/scene.h"
#include "device/geometric_haptic_contact.h"
#include "device/haptic_step.h"

namespace hapsim {
namespace {

struct Block {
  config::Scene scene;
  std::unique_ptr<config::Body> body;
};

const Block& GetBlock() {
  static std::unique_ptr<Block> block;
  if (block) return *block;
  block = std::make_unique<Block>();
  block->scene = config::LoadScene("scenes/block_press.yaml");
  block->body = std::make_unique<config::Body>(
      config::MakeBody(*block->scene.body, block->scene.gravity_m_s2));
  return *block;
}

void BM_GeometricStep(benchmark::State& state) {
  const Block& block = GetBlock();
  const device::HapticMode mode = state.range(0) == 0   ? device::HapticMode::kPenalty
                                  : state.range(0) == 1 ? device::HapticMode::kMaterial
                                                        : device::HapticMode::kImpact;
  const double depth_m = 1e-6 * static_cast<double>(state.range(1));
  ToolShape sphere;
  sphere.kind = ToolShape::Kind::kSphere;
  sphere.radius_m = 0.02;
  const ToolModel tool = MakeToolModelWithMass(sphere, 0.05);
  device::GeometricContactParams params;
  device::GeometricHapticContact geometric(mode, params, tool, &block.body->model, {});
  // The tool held still `depth` into the top (z = 0.03): the contact work of a step at that
  // pose (search and force), on the step system of a tool at rest with the device at it.
  ToolState held;
  held.x_W_m = Eigen::Vector3d(0.001, 0.0007, 0.03 + 0.02 - depth_m);
  const ToolStepSystem system = device::CalcLinearisationSystem(
      tool, block.scene.coupling, block.scene.gravity_m_s2, 1e-3, held);
  Eigen::Vector3d F, T;
  geometric.Calc(system, held, &F, &T);  // warm-up: the buffers grow
  for (auto _ : state) {
    geometric.Calc(system, held, &F, &T);
    benchmark::DoNotOptimize(F);
  }
  state.counters["contacts"] = geometric.num_contacts();
}

BENCHMARK(BM_GeometricStep)
    ->ArgNames({"mode", "depth_um"})
    ->ArgsProduct({{0, 1, 2}, {250, 1000, 2000, 4000, 8000}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hapsim

BENCHMARK_MAIN();
