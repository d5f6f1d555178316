#pragma once
// A shipped or test scene run through the in-process simulator, one sample per haptic step: the
// scene-level device tests' common harness (peg_in_hole_test, friction_lcp_test,
// probe_scene_test).

#include <cmath>
#include <vector>

#include "config/scene.h"
#include "config/simulation_builder.h"
#include "device/multirate_simulator.h"

namespace hapsim::device {

// `body` is the scene's built body (config::MakeSceneBody), or null for a rigid-only scene;
// num_steps < 0 runs the scene's whole script (time.num_steps frames).
inline std::vector<HapticSample> SimulateScene(const config::Scene& scene, HapticMode mode,
                                               const config::Body* body = nullptr,
                                               long num_steps = -1) {
  MultirateSimulator simulator(
      body ? &body->model : nullptr, body ? &scene.body->options : nullptr,
      body ? body->external_force_N : Eigen::VectorXd(), scene.tool->model,
      scene.tool->initial_state, config::MakeVisualFrameOptions(scene),
      config::MakeMultirateOptions(scene, mode, scene.haptic.steps_per_frame));
  if (num_steps < 0) num_steps = std::lround(scene.num_steps * scene.dt_s * scene.haptic.rate_hz);
  std::vector<HapticSample> samples;
  simulator.Run(
      ScriptedTrajectory(scene.trajectory), num_steps,
      [&](const HapticSample& s) { samples.push_back(s); }, nullptr);
  return samples;
}

}  // namespace hapsim::device
