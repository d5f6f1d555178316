#include "config/simulation_builder.h"

#include <optional>
#include <stdexcept>
#include <string>

#include "core/error.h"

namespace hapsim::config {

contact::VisualFrameOptions MakeVisualFrameOptions(const Scene& scene) {
  contact::VisualFrameOptions options;
  options.gravity_m_s2 = scene.gravity_m_s2;
  options.coupling = scene.coupling;
  options.detection.margin_m = scene.contact.margin_m;
  options.detection.feature_contacts = scene.contact.tool_features;
  options.detection.edge_contacts = scene.contact.tool_features;
  options.response.solve.law = scene.contact.law;
  options.response.solve.friction_coefficient = scene.contact.friction_coefficient;
  options.response.stabilization_beta = scene.contact.stabilization_beta;
  options.response.restitution = scene.contact.restitution;
  options.compliance = scene.contact.compliance;
  options.model_compliance_step = scene.contact.model_compliance_step;
  options.lcp_reach_m_s = scene.haptic.lcp_reach_m_s;
  options.lcp_max_rows = scene.haptic.lcp_max_rows;
  for (const RigidObjectScene& rigid : scene.rigid_objects)
    options.rigid_objects.push_back(rigid.object);
  if (scene.tool) options.grasp = scene.tool->grasp;
  return options;
}

contact::VisualFrame MakeVisualFrame(const Scene& scene, const std::optional<Body>& body,
                                     const contact::VisualFrameOptions& options) {
  if (!scene.tool) throw std::invalid_argument("MakeVisualFrame: the scene has no tool");
  return contact::VisualFrame(body ? &body->model : nullptr, body ? &scene.body->options : nullptr,
                              body ? body->external_force_N : Eigen::VectorXd(), scene.tool->model,
                              options);
}

device::HapticMode ResolveHapticMode(const Scene& scene, const std::string& option_value,
                                     const std::string& option, bool allow_reference) {
  const bool overridden = !option_value.empty();
  const std::string file = overridden ? "" : scene.file;
  const std::string key = overridden ? option : "haptic.mode";
  device::HapticMode mode = scene.haptic.mode;
  if (overridden) {
    const auto parsed = ParseHapticMode(option_value);
    if (!parsed)
      throw InputError("", 0, option,
                       "unknown mode '" + option_value +
                           "' (hybrid, linear, lcp, coupling, reference, penalty, material, "
                           "impact, godobject)");
    mode = *parsed;
  }
  if (mode == device::HapticMode::kGodObject && !(scene.tool && scene.tool->point))
    throw InputError(file, 0, key,
                     "the godobject mode renders a 3-DOF point: give tool.shape.point {radius_m}");
  if (mode == device::HapticMode::kReference && !allow_reference)
    throw InputError(file, 0, key,
                     "the reference mode runs in `hapsim sim` only; the two processes render "
                     "every other mode");
  if (const std::optional<std::string> why =
          WhyModelComplianceStepRefused(scene.contact.model_compliance_step, mode))
    throw InputError(scene.file, 0, "contact.model_compliance_step", *why);
  if (scene.tool && scene.tool->grasp)
    if (const std::optional<std::string> why = WhyGraspRefused(mode))
      throw InputError(file, 0, key, *why + " (the tool has a grasp)");
  return mode;
}

int LcpFrictionSweeps(const Scene& scene) {
  return scene.contact.law == contact::ContactLaw::kFriction ? scene.haptic.lcp_friction_sweeps : 0;
}

device::MultirateOptions MakeMultirateOptions(const Scene& scene, device::HapticMode mode,
                                              int steps_per_frame) {
  device::MultirateOptions options;
  options.mode = mode;
  options.haptic_dt_s = 1.0 / scene.haptic.rate_hz;
  options.haptic_steps_per_frame = steps_per_frame;
  options.lcp_max_rows = scene.haptic.lcp_max_rows;
  options.lcp_friction_sweeps = LcpFrictionSweeps(scene);
  options.geometric = scene.haptic.geometric;
  options.godobject = scene.haptic.godobject;
  if (scene.tool) options.godobject.proxy_radius_m = scene.tool->model.shape.radius_m;
  options.geometric.material.objects.clear();
  for (const RigidObjectScene& rigid : scene.rigid_objects)
    options.geometric.material.objects.push_back(rigid.material);
  return options;
}

}  // namespace hapsim::config
