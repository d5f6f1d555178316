// Google Benchmark: one whole haptic step (device read → coupling → free tool → contact → post-
// contact state → output) per mode, on the contact models and rows of real visual frames of
// scenes/block_press.yaml at peak press. Not a test: run `build/tests/haptic_step_benchmark` from
// the repository root (it reads scenes/).
//
//  BM_HapticStep/mode:0  linear    the paper's model (four 3×3 products)
//  BM_HapticStep/mode:1  lcp       the 1 kHz unilateral solve on the frame's rows, warm (same
//                                  rows as the step before: 29 of 30 steps of a frame)
//  BM_HapticStep/mode:2  lcp_first the first step of each frame (the rows of another frame at
//                                  every call) after HapticLcpSolver::Prepare, which the visual
//                                  frame or the haptic process's receive thread does off the
//                                  loop (not timed here; its cost is mode 4 minus this)
//  BM_HapticStep/mode:3  coupling  standard multirate: the coupling to the visual tool only
//  BM_HapticStep/mode:4  lcp_cold  the first step of each frame without Prepare: copy, check and
//                                  factorise inside the step
//  BM_HapticStep/mode:5  hybrid    the default mode (device/haptic_mode.h): the frame's active
//                                  rows held as equalities, the others unilateral, each free
//                                  row's target moved with the tool every step; warm, as mode 1
//
// BM_HapticFrictionStep/mode:1, 2, 4: the same lcp steps on scenes/block_press_friction.yaml
// (three rows per contact, the Coulomb solve at its haptic.lcp_friction_sweeps), or on the
// scene HAPSIM_BENCH_FRICTION_SCENE names (e.g. a copy with a smaller haptic.lcp_max_rows, to
// time the step without the frame's far, uncoupled candidates).
//
// Counters: rows (rows sent: 3 per contact with friction; of them uncoupled_rows, issue 13
// item 5), model_contacts (active contacts in the linear model).

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <string>

#include "config/body_builder.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "contact/visual_frame.h"
#include "core/scripted_trajectory.h"
#include "device/haptic_step.h"

namespace hapsim {
namespace {

constexpr double kPeakTime_s = 1.2;  // pressed 4 mm and sliding (scenes/block_press.yaml)

struct Frames {
  config::Scene scene;
  ToolState tool_at_peak;
  DeviceState device_at_peak;
  contact::LinearContactModel model[2];
  contact::ContactRows rows[2];  // two consecutive frames
};

// Runs the visual frames of the scene's script up to the peak and keeps the last two frames'
// outputs (once per scene).
const Frames& GetFrames(const std::string& scene_path) {
  static std::map<std::string, std::unique_ptr<Frames>> cache;
  std::unique_ptr<Frames>& frames = cache[scene_path];
  if (frames) return *frames;
  frames = std::make_unique<Frames>();
  Frames& f = *frames;
  f.scene = config::LoadScene(scene_path);
  const config::Body body = config::MakeBody(*f.scene.body, f.scene.gravity_m_s2);
  contact::VisualFrameOptions options = config::MakeVisualFrameOptions(f.scene);
  options.dt_s = f.scene.dt_s;
  options.haptic_dt_s = 1.0 / f.scene.haptic.rate_hz;
  options.export_contact_rows = true;
  contact::VisualFrame frame(body.model, f.scene.body->options, body.external_force_N,
                             f.scene.tool->model, options);
  fem::State body_state = fem::MakeRestState(body.model);
  ToolState tool = f.scene.tool->initial_state;
  const ScriptedTrajectory script(f.scene.trajectory);
  const int peak_frame = static_cast<int>(std::lround(kPeakTime_s / f.scene.dt_s));
  for (int k = 0; k <= peak_frame; ++k) {
    f.device_at_peak = script.Sample(k * f.scene.dt_s);
    frame.Step(f.device_at_peak, &body_state, &tool);
    f.model[k % 2] = frame.linear_model();
    f.rows[k % 2] = frame.contact_rows();
  }
  f.tool_at_peak = tool;
  return f;
}

void RunHapticStep(benchmark::State& bench, const std::string& scene_path) {
  const Frames& f = GetFrames(scene_path);
  const int mode = static_cast<int>(bench.range(0));
  const config::Scene& scene = f.scene;
  device::HapticStep step(scene.tool->model, scene.coupling, scene.gravity_m_s2,
                          1.0 / scene.haptic.rate_hz, f.tool_at_peak, scene.haptic.lcp_max_rows,
                          config::LcpFrictionSweeps(scene), /*hold_frame_contacts=*/mode == 5);
  step.SetContactModel(f.model[0]);
  if (mode == 1 || mode == 2 || mode == 4 || mode == 5) step.SetContactRows(&f.rows[0]);
  long calls = 0, fallbacks = 0;
  for (auto _ : bench) {
    if (mode == 2) {
      bench.PauseTiming();
      step.PrepareContactRows(f.rows[++calls % 2]);
      step.SetContactRows(&f.rows[calls % 2]);
      bench.ResumeTiming();
    }
    if (mode == 4) step.SetContactRows(&f.rows[++calls % 2]);
    if (mode == 3) {
      const CouplingWrench wrench =
          CalcCouplingWrench(scene.coupling, f.device_at_peak, f.tool_at_peak,
                             CalcAngularVelocity(scene.tool->model, f.tool_at_peak));
      benchmark::DoNotOptimize(wrench);
      continue;
    }
    const device::HapticOutput out = step.Step(f.device_at_peak);
    fallbacks += out.lcp_fell_back;
    benchmark::DoNotOptimize(out);
  }
  bench.counters["rows"] = f.rows[0].num_rows();
  bench.counters["uncoupled_rows"] = f.rows[0].num_uncoupled_rows;
  bench.counters["model_contacts"] = f.model[0].num_contacts;
  bench.counters["lcp_fallbacks"] = static_cast<double>(fallbacks);
}

void BM_HapticStep(benchmark::State& bench) { RunHapticStep(bench, "scenes/block_press.yaml"); }
void BM_HapticFrictionStep(benchmark::State& bench) {
  RunHapticStep(bench, std::getenv("HAPSIM_BENCH_FRICTION_SCENE") != nullptr
                           ? std::getenv("HAPSIM_BENCH_FRICTION_SCENE")
                           : "scenes/block_press_friction.yaml");
}

BENCHMARK(BM_HapticStep)->DenseRange(0, 5)->ArgName("mode")->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_HapticFrictionStep)
    ->Arg(1)
    ->Arg(2)
    ->Arg(4)
    ->ArgName("mode")
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace hapsim

BENCHMARK_MAIN();
