#include "device/multirate_simulator.h"

#include <stdexcept>
#include <utility>

#include "core/stopwatch.h"

namespace hapsim::device {
namespace {

contact::VisualFrameOptions WithStep(contact::VisualFrameOptions visual,
                                     const MultirateOptions& o) {
  const int ratio = o.mode == HapticMode::kReference ? 1 : o.haptic_steps_per_frame;
  return SetUpFrameForMode(std::move(visual), o.mode, ratio * o.haptic_dt_s, o.haptic_dt_s);
}

}  // namespace

contact::VisualFrameOptions SetUpFrameForMode(contact::VisualFrameOptions visual, HapticMode mode,
                                              double visual_dt_s, double haptic_dt_s) {
  visual.dt_s = visual_dt_s;
  visual.haptic_dt_s = haptic_dt_s;
  visual.export_contact_rows = UsesContactRows(mode);
  visual.model_compliance_step =
      ResolveModelComplianceStep(visual.model_compliance_step, mode, visual_dt_s);
  // The ground truth takes no shortcut: the exact compliance, whatever the scene chose, and the
  // contact correction to the scene's solver tolerance.
  if (mode == HapticMode::kReference) {
    visual.compliance = contact::ComplianceMethod::kExact;
    visual.correction_relative_tolerance = 0.0;
    visual.free_body_correction_relative_tolerance = 0.0;
  }
  return visual;
}

contact::ModelComplianceStep ResolveModelComplianceStep(contact::ModelComplianceStep step,
                                                        HapticMode mode, double visual_dt_s) {
  if (step != contact::ModelComplianceStep::kAuto) return step;
  return mode == HapticMode::kHybrid && visual_dt_s * kHapticComplianceBelowHz > 1.0
             ? contact::ModelComplianceStep::kHaptic
             : contact::ModelComplianceStep::kVisual;
}

const char* ToString(HapticMode mode) {
  switch (mode) {
    case HapticMode::kHybrid:
      return "hybrid";
    case HapticMode::kLinear:
      return "linear";
    case HapticMode::kLcp:
      return "lcp";
    case HapticMode::kCoupling:
      return "coupling";
    case HapticMode::kReference:
      return "reference";
    case HapticMode::kPenalty:
      return "penalty";
    case HapticMode::kMaterial:
      return "material";
    case HapticMode::kImpact:
      return "impact";
    case HapticMode::kGodObject:
      return "godobject";
  }
  return "?";
}

MultirateSimulator::MultirateSimulator(const fem::Model& body, const fem::FemOptions& fem_options,
                                       const Eigen::VectorXd& body_external_force_N,
                                       const ToolModel& tool, const ToolState& initial_tool,
                                       contact::VisualFrameOptions visual_options,
                                       const MultirateOptions& options)
    : MultirateSimulator(&body, &fem_options, body_external_force_N, tool, initial_tool,
                         std::move(visual_options), options) {}

MultirateSimulator::MultirateSimulator(const fem::Model* body, const fem::FemOptions* fem_options,
                                       const Eigen::VectorXd& body_external_force_N,
                                       const ToolModel& tool, const ToolState& initial_tool,
                                       contact::VisualFrameOptions visual_options,
                                       const MultirateOptions& options)
    : options_(options),
      visual_options_(WithStep(std::move(visual_options), options)),
      frame_(body, fem_options, body_external_force_N, tool, visual_options_),
      body_state_(body ? fem::MakeRestState(*body) : fem::State{}),
      visual_tool_(initial_tool),
      haptic_(tool, visual_options_.coupling, visual_options_.gravity_m_s2, options.haptic_dt_s,
              initial_tool, UsesContactRows(options.mode) ? options.lcp_max_rows : 0,
              UsesContactRows(options.mode) ? options.lcp_friction_sweeps : 0,
              HoldsFrameContacts(options.mode)) {
  if (options.haptic_steps_per_frame < 1) throw std::invalid_argument("haptic_steps_per_frame < 1");
  observed_tool_x_W_m_ = initial_tool.x_W_m;
  if (IsGeometricMode(options.mode)) {
    geometric_ = std::make_unique<GeometricHapticContact>(options.mode, options.geometric, tool,
                                                          body, visual_options_.rigid_objects);
    haptic_.SetGeometricContact(geometric_.get());
  }
  if (options.mode == HapticMode::kGodObject) {
    god_world_ =
        std::make_unique<GodObjectWorld>(options.godobject, body, visual_options_.rigid_objects);
    god_world_->god_object().Reset(initial_tool.x_W_m);
  }
}

void MultirateSimulator::Run(const ScriptedTrajectory& trajectory, long num_haptic_steps,
                             const std::function<void(const HapticSample&)>& on_haptic_step,
                             const std::function<void(const FrameSample&)>& on_frame) {
  ScriptedDevice device(trajectory);
  Run(&device, num_haptic_steps, on_haptic_step, on_frame);
}

void MultirateSimulator::Run(DeviceBackend* backend, long num_haptic_steps,
                             const std::function<void(const HapticSample&)>& on_haptic_step,
                             const std::function<void(const FrameSample&)>& on_frame) {
  on_frame_ = on_frame;
  for (long k = 0; k < num_haptic_steps; ++k) {
    double age_s = 0.0;
    long sequence = 0;
    const DeviceState device = backend->Read(k * options_.haptic_dt_s, &age_s, &sequence);
    HapticSample sample;
    switch (options_.mode) {
      case HapticMode::kHybrid:
      case HapticMode::kLinear:
      case HapticMode::kLcp:
      case HapticMode::kPenalty:
      case HapticMode::kMaterial:
      case HapticMode::kImpact:
        sample = StepHapticTool(device, k);
        break;
      case HapticMode::kCoupling:
        sample = StepCoupling(device, k);
        break;
      case HapticMode::kReference:
        sample = StepReference(device, k);
        break;
      case HapticMode::kGodObject:
        sample = StepGodObject(device, k);
        break;
    }
    sample.t_s = k * options_.haptic_dt_s;
    sample.device_x_W_m = device.x_W_m;
    backend->Write(sample.device_force_W_N, sample.device_torque_W_N_m);
    // The wrench sent this step paired with the handle's velocity read for it (Hannaford & Ryu),
    // and gravity's work on the rendered tool over the step (godobject's proxy has no weight).
    // (The in-process simulator has no safety layer: what is rendered is sent.) A non-finite
    // tool position is not taken as the next reference.
    const bool finite = sample.tool_x_W_m.allFinite();
    const double gravity_work_J =
        options_.mode != HapticMode::kGodObject && finite
            ? CalcGravityWork(frame_.tool_model().mass_kg, visual_options_.gravity_m_s2,
                              observed_tool_x_W_m_, sample.tool_x_W_m)
            : 0.0;
    if (finite) observed_tool_x_W_m_ = sample.tool_x_W_m;
    passivity_.Update(sample.device_force_W_N, sample.device_torque_W_N_m, device.v_W_m_s,
                      device.w_W_rad_s, options_.haptic_dt_s, gravity_work_J);
    sample.passivity_energy_J = passivity_.energy_in_J();
    if (on_haptic_step) on_haptic_step(sample);
  }
}

// Paper mode: two instances of the tool, both coupled to the device (the paper's Fig. 1): the
// visual tool in the full simulation at the visual rate, the haptic tool at 1 kHz with the linear
// contact model (or, lcp, the contact rows) of the last visual frame.
HapticSample MultirateSimulator::StepHapticTool(const DeviceState& device, long k) {
  const bool lcp = UsesContactRows(options_.mode);
  if (k % options_.haptic_steps_per_frame == 0) {
    const contact::VisualFrameStats stats =
        frame_.Step(device, &body_state_, &visual_tool_, &haptic_.tool_state());
    haptic_.SetContactModel(frame_.linear_model());
    if (lcp) {  // the first step's factorisation is frame work (as off the loop in two processes)
      haptic_.PrepareContactRows(frame_.contact_rows());
      haptic_.SetContactRows(&frame_.contact_rows());
    }
    if (geometric_) SetGeometricWorld();
    last_frame_step_ = k;
    if (on_frame_) on_frame_(MakeFrameSample(k, stats));
  }
  Stopwatch stopwatch;
  const HapticOutput out = haptic_.Step(device);
  HapticSample sample;
  sample.step_time_s = stopwatch.Elapsed() + TakeWorldTime(k);
  sample.device_force_W_N = out.device_force_W_N;
  sample.device_torque_W_N_m = out.device_torque_W_N_m;
  sample.contact_force_W_N = out.contact_force_W_N;
  sample.tool_x_W_m = haptic_.tool_state().x_W_m;
  sample.tool_q_WT = haptic_.tool_state().q_WT;
  sample.num_contacts = geometric_ ? geometric_->num_contacts()
                        : lcp      ? frame_.contact_rows().num_rows()
                                   : frame_.linear_model().num_contacts;
  sample.lcp_fell_back = out.lcp_fell_back;
  sample.model_age_s = (k - last_frame_step_) * options_.haptic_dt_s;
  return sample;
}

// The device force of the two modes without a haptic tool: the coupling's reaction to the
// visual tool as it stands.
void MultirateSimulator::FillFromVisualTool(const DeviceState& device, HapticSample* sample) const {
  const CouplingWrench wrench =
      CalcCouplingWrench(visual_options_.coupling, device, visual_tool_,
                         CalcAngularVelocity(frame_.tool_model(), visual_tool_));
  sample->device_force_W_N = -wrench.F_W_N;
  sample->device_torque_W_N_m = -wrench.T_W_N_m;
}

FrameSample MultirateSimulator::MakeFrameSample(long k,
                                                const contact::VisualFrameStats& stats) const {
  FrameSample sample;
  sample.t_s = k * options_.haptic_dt_s;
  sample.stats = stats;
  sample.tool_x_W_m = visual_tool_.x_W_m;
  sample.contact_force_W_N = frame_.contact_force_N();
  return sample;
}

void MultirateSimulator::FillFromLastFrame(HapticSample* sample) const {
  sample->contact_force_W_N = frame_.contact_force_N();
  sample->tool_x_W_m = visual_tool_.x_W_m;
  sample->tool_q_WT = visual_tool_.q_WT;
  sample->num_contacts = static_cast<int>(frame_.contacts().size());
}

// Standard multirate: the visual tool, coupled to the device, moves only at visual frames; the
// device feels the coupling to it, held between frames.
HapticSample MultirateSimulator::StepCoupling(const DeviceState& device, long k) {
  if (k % options_.haptic_steps_per_frame == 0) {
    const contact::VisualFrameStats stats = frame_.Step(device, &body_state_, &visual_tool_);
    last_frame_step_ = k;
    if (on_frame_) on_frame_(MakeFrameSample(k, stats));
  }
  HapticSample sample;
  FillFromVisualTool(device, &sample);
  FillFromLastFrame(&sample);
  sample.model_age_s = (k - last_frame_step_) * options_.haptic_dt_s;
  return sample;
}

// Ground truth: a whole visual frame every haptic step; the device feels the coupling to the tool
// at the start of the step, as in the haptic step of the other modes.
HapticSample MultirateSimulator::StepReference(const DeviceState& device, long k) {
  HapticSample sample;
  FillFromVisualTool(device, &sample);
  const contact::VisualFrameStats stats = frame_.Step(device, &body_state_, &visual_tool_);
  if (on_frame_) on_frame_(MakeFrameSample(k, stats));
  FillFromLastFrame(&sample);
  return sample;
}

// The frame's world put in place for the 1 kHz modes, timed: the two-process loop does this in
// the first step on a model, so it belongs to that step's cost.
void MultirateSimulator::SetGeometricWorld() {
  Stopwatch stopwatch;
  object_poses_.resize(frame_.num_objects());
  for (int i = 0; i < frame_.num_objects(); ++i) object_poses_[i] = frame_.object_pose(i);
  if (geometric_) geometric_->SetWorld(body_state_.x_m, object_poses_);
  if (god_world_) god_world_->SetWorld(body_state_.x_m, object_poses_);
  world_time_s_ = stopwatch.Elapsed();
}

double MultirateSimulator::TakeWorldTime(long k) {
  if (k % options_.haptic_steps_per_frame != 0) return 0.0;
  const double seconds = world_time_s_;
  world_time_s_ = 0.0;
  return seconds;
}

// God-object (paper 004): at 1 kHz the god-object places the proxy for the device's point on the
// last frame's surfaces and the device feels k (proxy − point). The visual tool, a sphere of the
// proxy's radius, is coupled to the device as in the coupling mode, so that the body deforms
// under what the hand does (a visual tool coupled to the proxy would rest on the undeformed
// surface and never press it); with the god-object's k equal to the coupling's, the body carries
// the force the device feels.
HapticSample MultirateSimulator::StepGodObject(const DeviceState& device, long k) {
  contact::GodObject& god = god_world_->god_object();
  if (k % options_.haptic_steps_per_frame == 0) {
    const contact::VisualFrameStats stats = frame_.Step(device, &body_state_, &visual_tool_);
    SetGeometricWorld();
    last_frame_step_ = k;
    if (on_frame_) on_frame_(MakeFrameSample(k, stats));
  }
  Stopwatch stopwatch;
  god.Step(device.x_W_m);
  HapticSample sample;
  sample.step_time_s = stopwatch.Elapsed() + TakeWorldTime(k);
  sample.device_force_W_N = god.force_W_N();
  sample.contact_force_W_N = god.force_W_N();  // the surfaces hold the proxy against the spring
  sample.tool_x_W_m = god.proxy_W_m();
  sample.num_contacts = god.num_active_constraints();
  sample.model_age_s = (k - last_frame_step_) * options_.haptic_dt_s;
  return sample;
}

}  // namespace hapsim::device
