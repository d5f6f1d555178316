#pragma once
// The work of one step of the separate 1 kHz haptic process (DESIGN.md §5, issue 4), without
// its clock or its I/O, so that `hapsim haptic` runs it against wall time and `hapsim replay`
// re-runs it from a log and gets the same forces bit for bit:
//   1 take the newest contact model, if one arrived (linear model, and the rows in lcp mode)
//   2 the haptic step (device/haptic_step.h) — skipped on a non-finite device state, which would
//     poison the haptic tool's state; in the coupling mode instead the coupling between the
//     device and the visual tool of the last frame, held until the next (standard multirate);
//     in the geometric modes and godobject the step renders the world the model carried
//     (device/geometric_haptic_contact.h, device/god_object_world.h), put in place first
//   3 the safety layer (device/haptic_safety.h): NaN/stale → zero, blend, rate limit, clamp
//   4 the passivity observer on what was actually sent (device/passivity_observer.h), with
//     gravity's work on the rendered tool as a second port (its weight is not generated energy)
// Deterministic: the output depends only on the sequence of (device state, device age, model)
// given to Step. Allocates nothing after construction (the lcp solver is sized by
// lcp_max_rows).

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "device/geometric_haptic_contact.h"
#include "device/god_object_world.h"
#include "device/haptic_mode.h"
#include "device/haptic_safety.h"
#include "device/haptic_step.h"
#include "device/model_mailbox.h"
#include "device/passivity_observer.h"

namespace hapsim::device {

struct HapticLoopOptions {
  HapticMode mode = kDefaultHapticMode;  // any but reference
  double dt_s = 1e-3;
  int lcp_max_rows = 512;
  int lcp_friction_sweeps = 0;  // > 0: the lcp solver takes friction rows (the friction law)
  SafetyLimits safety;
  double passivity_threshold_J = 1e-3;
  // The geometric modes (penalty, material, impact) and godobject: their parameters, and the
  // size of the world every contact model must carry (the scene's body nodes and rigid objects).
  GeometricContactParams geometric;
  contact::GodObjectParams godobject;
  int world_nodes = 0;
  int world_objects = 0;
};

struct HapticLoopOutput {
  HapticOutput rendered;  // what the haptic step computed (zero when skipped)
  SafeWrench sent;        // what may go to the device
  std::int64_t model_sequence = -1;
  double model_age_s = std::numeric_limits<double>::infinity();
  double passivity_energy_J = 0.0;
  bool passivity_alarm = false;  // the observer turned active at this step
  bool lcp_fell_back = false;    // lcp: the solve failed and the linear model was used
};

class HapticLoop {
 public:
  // Throws std::invalid_argument for the reference mode (in-process only), bad safety limits, or
  // bad parameters of the papers' modes (penalty, material, impact, god-object: as their
  // classes do). body, objects: the world of the geometric modes and godobject (the scene's
  // deformable body, which must outlive the loop, or null; its rigid objects at their start
  // poses); every model's world must have their sizes (else it is not applied).
  HapticLoop(const ToolModel& tool, const CouplingParams& coupling,
             const Eigen::Vector3d& gravity_m_s2, const ToolState& initial_tool,
             const HapticLoopOptions& options, const fem::Model* body = nullptr,
             const std::vector<contact::RigidObject>& objects = {});

  // One step. device_age_s: how old `device` is; new_model: the update that arrived since the
  // last step, or nullptr (it must stay unchanged until the next non-null new_model).
  HapticLoopOutput Step(const DeviceState& device, double device_age_s,
                        const ContactModelUpdate* new_model) noexcept;

  // The haptic tool (linear, lcp, geometric modes), the visual tool of the last frame
  // (coupling), or a tool at the god-object's proxy (godobject).
  const ToolState& tool_state() const {
    if (options_.mode == HapticMode::kCoupling) return visual_tool_;
    return options_.mode == HapticMode::kGodObject ? proxy_tool_ : step_.tool_state();
  }
  long num_steps() const { return num_steps_; }
  const HapticStep& haptic_step() const { return step_; }

 private:
  HapticLoopOptions options_;
  HapticStep step_;
  ToolState visual_tool_;                              // coupling mode
  std::unique_ptr<GeometricHapticContact> geometric_;  // penalty, material, impact
  std::unique_ptr<GodObjectWorld> god_world_;          // godobject
  ToolState proxy_tool_;                               // godobject: at the proxy
  int world_nodes_ = 0;    // the size of a world this loop renders (its body's nodes,
  int world_objects_ = 0;  // its rigid objects); a model's world of another size is not applied
  HapticSafety safety_;
  PassivityObserver passivity_;
  // Where the rendered tool stood at the observer's last sample: gravity's work on it since then
  // is counted as energy flowed in (device/passivity_observer.h). godobject's proxy has no weight.
  Eigen::Vector3d observed_tool_x_W_m_ = Eigen::Vector3d::Zero();
  std::int64_t model_sequence_ = -1;
  double model_age_s_ = std::numeric_limits<double>::infinity();
  long num_steps_ = 0;
};

// Gives the update an lcp solver of options.lcp_max_rows rows (and lcp_friction_sweeps) unless
// it has one (~16 lcp_max_rows² bytes, 8 more with friction). PrepareLcpUpdate calls it; `hapsim haptic` calls it for every mailbox
// slot before the loop starts, so that no model waits for an allocation (the first three models
// of an lcp run once waited 3–4 ms each, page faults under mlockall included).
void EnsureLcpSolver(const HapticLoopOptions& options, ContactModelUpdate* update);

// Receive-thread work for an lcp update: gives it a solver (once: max_rows capacity) and prepares
// it for the update's rows at its linearised tool, so the loop's first step on them is warm. Same
// inputs, same solver state: `hapsim replay` calls it too. Returns false if the rows were
// rejected (the loop then falls back to the linear model, as for a failed solve).
bool PrepareLcpUpdate(const ToolModel& tool, const CouplingParams& coupling,
                      const Eigen::Vector3d& gravity_m_s2, const HapticLoopOptions& options,
                      ContactModelUpdate* update);

// Every entry of the device state is finite (quaternion included).
bool IsFinite(const DeviceState& device);

}  // namespace hapsim::device
