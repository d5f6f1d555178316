#include "config/simulation_builder.h"

#include "core/error.h"

namespace hapsim::config {

contact::VisualFrameOptions MakeVisualFrameOptions(const Scene& scene) {
  contact::VisualFrameOptions options;
  options.gravity_m_s2 = scene.gravity_m_s2;
  options.coupling = scene.coupling;
  options.detection.margin_m = scene.contact.margin_m;
  options.response.solve.law = scene.contact.law;
  options.response.solve.friction_coefficient = scene.contact.friction_coefficient;
  options.response.stabilization_beta = scene.contact.stabilization_beta;
  options.response.restitution = scene.contact.restitution;
  options.compliance = scene.contact.compliance;
  return options;
}

device::MultirateOptions MakeMultirateOptions(const Scene& scene, device::HapticMode mode,
                                              int steps_per_frame, const std::string& mode_option) {
  if (mode == device::HapticMode::kLcp && scene.contact.law == contact::ContactLaw::kFriction)
    throw InputError("", 0, mode_option,
                     "lcp solves normal rows only; the scene's contact law is friction");
  device::MultirateOptions options;
  options.mode = mode;
  options.haptic_dt_s = 1.0 / scene.haptic.rate_hz;
  options.haptic_steps_per_frame = steps_per_frame;
  options.lcp_max_rows = scene.haptic.lcp_max_rows;
  return options;
}

}  // namespace hapsim::config
