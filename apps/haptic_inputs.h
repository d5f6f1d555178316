#pragma once
// The inputs of the haptic loop as both `hapsim haptic` (live) and `hapsim replay` (from a log)
// build them: one piece of code, because replay reproduces the live forces bit for bit only if
// it feeds the loop exactly what the live process did.

#include <algorithm>
#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "config/body_builder.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "core/realtime.h"
#include "device/device_backend.h"
#include "device/haptic_loop.h"
#include "device/model_mailbox.h"
#include "messages/adapters.h"
#include "messages/message_gate.h"

namespace hapsim::apps {

// What the geometric modes and godobject render in the haptic process: the scene's deformable
// body (built only for those modes; it must outlive the loop) and rigid objects, which each
// contact model then moves to where its frame left them.
struct HapticWorld {
  std::optional<config::Body> body;
  std::vector<contact::RigidObject> objects;
  const fem::Model* body_model() const { return body ? &body->model : nullptr; }
};

inline HapticWorld MakeHapticWorld(const config::Scene& scene, device::HapticMode mode) {
  HapticWorld world;
  if (!device::NeedsWorld(mode)) return world;
  world.body = config::MakeSceneBody(scene);
  for (const config::RigidObjectScene& rigid : scene.rigid_objects)
    world.objects.push_back(rigid.object);
  return world;
}

// The loop's options for `mode` from the scene (haptic rate, lcp capacity, safety limits, the
// papers' modes' parameters as `hapsim sim` takes them) and the world it renders.
inline device::HapticLoopOptions MakeHapticLoopOptions(const config::Scene& scene,
                                                       device::HapticMode mode,
                                                       const HapticWorld& world) {
  device::HapticLoopOptions options;
  options.mode = mode;
  options.dt_s = 1.0 / scene.haptic.rate_hz;
  options.lcp_max_rows = scene.haptic.lcp_max_rows;
  options.lcp_friction_sweeps = config::LcpFrictionSweeps(scene);
  options.safety = scene.haptic.safety;
  const device::MultirateOptions in_process =
      config::MakeMultirateOptions(scene, mode, std::max(1, scene.haptic.steps_per_frame));
  options.geometric = in_process.geometric;
  options.godobject = in_process.godobject;
  if (device::NeedsWorld(mode)) {
    options.world_nodes = world.body ? world.body->model.num_nodes() : 0;
    options.world_objects = static_cast<int>(world.objects.size());
  }
  return options;
}

// Decodes a CONTACT_MODEL into an update (model, rows, visual tool, linearisation pose, and in
// the geometric modes and godobject the frame's world, which must match the scene's) and, in the
// lcp mode, prepares its solver (device::PrepareLcpUpdate). Returns false with *error on a
// message the adapters reject; a rejected lcp preparation is not an error (the loop falls back
// to the linear model and counts it).
inline bool ReadContactModelUpdate(const hapsim_lcm::contact_model_t& msg,
                                   const config::ToolScene& tool, const CouplingParams& coupling,
                                   const Eigen::Vector3d& gravity_m_s2,
                                   const device::HapticLoopOptions& options,
                                   device::ContactModelUpdate* update, std::string* error) {
  messages::ContactModelHeader header;
  if (!messages::FromMessage(msg, &update->model, &update->rows, &header, error)) return false;
  // Built for another haptic step, its tool matrices would be wrong for this loop.
  if (std::abs(header.dt_haptic_s - options.dt_s) > 1e-9 * options.dt_s) {
    *error = "contact_model_t.dt_haptic_s: " + std::to_string(header.dt_haptic_s) +
             " s, but this loop steps " + std::to_string(options.dt_s) + " s";
    return false;
  }
  update->sequence = header.sequence;
  update->published_utime = header.utime;
  update->visual_tool = header.visual_tool;
  update->linearised_tool = ToolState{};
  update->linearised_tool.x_W_m = header.x_W_m;
  update->linearised_tool.q_WT = header.q_WT;
  update->has_world = false;
  if (device::NeedsWorld(options.mode)) {
    if (!messages::WorldFromMessage(msg, options.world_nodes, options.world_objects,
                                    &update->body_x_m, &update->object_poses, &update->has_world,
                                    error))
      return false;
    // A scene with a body or objects always sends them in these modes: none means the visual
    // process renders another mode.
    if (!update->has_world && options.world_nodes + options.world_objects > 0) {
      *error = "contact_model_t carries no world: the visual process must run the " +
               std::string(device::ToString(options.mode)) + " mode too";
      return false;
    }
  }
  device::PrepareLcpUpdate(tool.model, coupling, gravity_m_s2, options, update);
  return true;
}

// A device state that failed validation, or none at all yet: not finite, so the safety layer
// answers it with zero force.
inline DeviceState MakeInvalidDeviceState() {
  DeviceState none;
  none.x_W_m.setConstant(std::numeric_limits<double>::quiet_NaN());
  return none;
}

// A DEVICE_STATE as the loop sees it (MakeInvalidDeviceState when it fails validation).
inline DeviceState ReadDeviceState(const hapsim_lcm::device_state_t& msg) {
  DeviceState state;
  std::string error;
  return messages::FromMessage(msg, &state, &error) ? state : MakeInvalidDeviceState();
}

// DEVICE_STATE from an external driver process (docs/DEVICE.md). The receive thread decodes
// each message of this run (the gate drops malformed ones and other runs') into a triple buffer;
// the loop reads the newest and its age. A state that fails validation (a bad quaternion) arrives
// as NaN, so the safety layer answers it with zero force.
class ExternalDevice : public device::DeviceBackend {
 public:
  explicit ExternalDevice(messages::MessageGate* gate) : gate_(gate) {}
  struct Sample {
    DeviceState state;
    std::int64_t sequence = -1;
    std::int64_t received_ns = 0;
  };
  void Handle(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    hapsim_lcm::device_state_t msg;
    if (!gate_->Admit(buffer, channel, &msg)) return;
    Sample* slot = buffer_.writer_slot();
    slot->state = ReadDeviceState(msg);
    slot->sequence = msg.sequence;
    slot->received_ns = MonotonicNs();
    buffer_.Publish();
  }
  DeviceState Read(double, double* age_s, long* sequence) override {
    if (const Sample* newest = buffer_.TakeNewest()) latest_ = *newest;
    *sequence = latest_.sequence;
    if (latest_.sequence < 0) {  // nothing yet: not finite, infinitely old
      *age_s = std::numeric_limits<double>::infinity();
      return MakeInvalidDeviceState();
    }
    *age_s = 1e-9 * static_cast<double>(MonotonicNs() - latest_.received_ns);
    return latest_.state;
  }
  void Write(const Eigen::Vector3d&, const Eigen::Vector3d&) override {}  // DEVICE_FORCE

 private:
  messages::MessageGate* gate_;
  device::TripleBuffer<Sample> buffer_;
  Sample latest_;
};

}  // namespace hapsim::apps
