#include "device/haptic_loop.h"

#include <stdexcept>

namespace hapsim::device {

bool IsFinite(const DeviceState& device) {
  return device.x_W_m.allFinite() && device.v_W_m_s.allFinite() &&
         device.q_WD.coeffs().allFinite() && device.w_W_rad_s.allFinite();
}

HapticLoop::HapticLoop(const ToolModel& tool, const CouplingParams& coupling,
                       const Eigen::Vector3d& gravity_m_s2, const ToolState& initial_tool,
                       const HapticLoopOptions& options, const fem::Model* body,
                       const std::vector<contact::RigidObject>& objects)
    : options_(options),
      step_(tool, coupling, gravity_m_s2, options.dt_s, initial_tool,
            UsesContactRows(options.mode) ? options.lcp_max_rows : 0,
            UsesContactRows(options.mode) ? options.lcp_friction_sweeps : 0,
            HoldsFrameContacts(options.mode)),
      visual_tool_(initial_tool),
      proxy_tool_(initial_tool),
      world_nodes_(body != nullptr ? body->num_nodes() : 0),
      world_objects_(static_cast<int>(objects.size())),
      safety_(options.safety, options.dt_s),
      passivity_(options.passivity_threshold_J),
      observed_tool_x_W_m_(initial_tool.x_W_m) {
  if (options.mode == HapticMode::kReference)
    throw std::invalid_argument("the reference mode runs in the in-process simulator only");
  if (IsGeometricMode(options.mode)) {
    geometric_ = std::make_unique<GeometricHapticContact>(options.mode, options.geometric, tool,
                                                          body, objects);
    step_.SetGeometricContact(geometric_.get());
  }
  if (options.mode == HapticMode::kGodObject) {
    god_world_ = std::make_unique<GodObjectWorld>(options.godobject, body, objects);
    god_world_->god_object().Reset(initial_tool.x_W_m);
  }
}

void EnsureLcpSolver(const HapticLoopOptions& options, ContactModelUpdate* update) {
  const bool hold = HoldsFrameContacts(options.mode);
  if (!update->lcp_solver || update->lcp_solver->max_rows() != options.lcp_max_rows ||
      update->lcp_solver->friction_sweeps() != options.lcp_friction_sweeps ||
      update->lcp_solver->hold_frame_contacts() != hold)
    update->lcp_solver = std::make_unique<contact::HapticLcpSolver>(
        options.lcp_max_rows, options.lcp_friction_sweeps, hold, kLcpSolvesPerStep);
}

bool PrepareLcpUpdate(const ToolModel& tool, const CouplingParams& coupling,
                      const Eigen::Vector3d& gravity_m_s2, const HapticLoopOptions& options,
                      ContactModelUpdate* update) {
  if (!UsesContactRows(options.mode) || update->rows.num_rows() == 0) return true;
  EnsureLcpSolver(options, update);
  return update->lcp_solver->Prepare(
      update->rows,
      CalcLinearisationSystem(tool, coupling, gravity_m_s2, options.dt_s, update->linearised_tool));
}

HapticLoopOutput HapticLoop::Step(const DeviceState& device, double device_age_s,
                                  const ContactModelUpdate* new_model) noexcept {
  HapticLoopOutput out;
  // 1. The newest model: from this step on (age 0 at the step it arrives).
  if (new_model != nullptr) {
    step_.SetContactModel(new_model->model);
    if (UsesContactRows(options_.mode))
      step_.SetContactRows(new_model->rows.num_rows() > 0 ? &new_model->rows : nullptr,
                           new_model->lcp_solver.get(), &new_model->linearised_tool);
    visual_tool_ = new_model->visual_tool;
    // The world to render from this step on (a refit of the body's tree: once a frame). One of
    // another size than the loop's (the receiver checks it against the scene) is not applied:
    // the world setters would throw, and this step must not.
    const bool world_fits =
        new_model->has_world &&
        new_model->body_x_m.size() == 3 * static_cast<Eigen::Index>(world_nodes_) &&
        static_cast<int>(new_model->object_poses.size()) == world_objects_;
    if (world_fits && geometric_)
      geometric_->SetWorld(new_model->body_x_m, new_model->object_poses);
    if (world_fits && god_world_)
      god_world_->SetWorld(new_model->body_x_m, new_model->object_poses);
    model_sequence_ = new_model->sequence;
    model_age_s_ = 0.0;
  } else if (model_sequence_ >= 0) {
    model_age_s_ += options_.dt_s;
  }
  // 2. The haptic step, on a finite device state only.
  const bool device_finite = IsFinite(device);
  if (device_finite && options_.mode == HapticMode::kCoupling) {
    const CouplingWrench wrench =
        CalcCouplingWrench(step_.coupling(), device, visual_tool_,
                           CalcAngularVelocity(step_.tool_model(), visual_tool_));
    out.rendered.device_force_W_N = -wrench.F_W_N;
    out.rendered.device_torque_W_N_m = -wrench.T_W_N_m;
  } else if (device_finite && god_world_) {
    contact::GodObject& god = god_world_->god_object();
    god.Step(device.x_W_m);
    out.rendered.device_force_W_N = god.force_W_N();
    out.rendered.contact_force_W_N = god.force_W_N();  // the surfaces hold the proxy
    proxy_tool_.x_W_m = god.proxy_W_m();
  } else if (device_finite) {
    out.rendered = step_.Step(device);
  }
  // 3. Safety.
  SafetyInputs inputs;
  inputs.device_age_s = device_age_s;
  inputs.model_age_s = model_age_s_;
  inputs.new_model = new_model != nullptr;
  inputs.device_finite = device_finite;
  out.sent =
      safety_.Filter(out.rendered.device_force_W_N, out.rendered.device_torque_W_N_m, inputs);
  // 4. Passivity of what was sent.
  const bool was_active = passivity_.active();
  if (device_finite) {
    // Gravity's work counts only while the hand is sent the rendering: a wrench the safety layer
    // zeroed (no model, a stale device or model, a non-finite wrench) does not carry the tool's
    // weight to the port, and crediting its descent then would bank energy that hides a later
    // fault. (Blends and rate limits pass the weight on, late: credited.) A non-finite tool
    // position is not taken as the next reference.
    const Eigen::Vector3d& tool_x_W_m = tool_state().x_W_m;
    const bool finite = tool_x_W_m.allFinite();
    const double gravity_work_J =
        options_.mode != HapticMode::kGodObject && !out.sent.zeroed && finite
            ? CalcGravityWork(step_.tool_model().mass_kg, step_.gravity_m_s2(),
                              observed_tool_x_W_m_, tool_x_W_m)
            : 0.0;
    if (finite) observed_tool_x_W_m_ = tool_x_W_m;
    passivity_.Update(out.sent.force_W_N, out.sent.torque_W_N_m, device.v_W_m_s, device.w_W_rad_s,
                      options_.dt_s, gravity_work_J);
  }
  out.passivity_energy_J = passivity_.energy_in_J();
  out.passivity_alarm = passivity_.active() && !was_active;
  out.lcp_fell_back = out.rendered.lcp_fell_back;
  out.model_sequence = model_sequence_;
  out.model_age_s = model_age_s_;
  ++num_steps_;
  return out;
}

}  // namespace hapsim::device
