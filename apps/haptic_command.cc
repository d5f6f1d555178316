// `hapsim haptic SCENE`: the separate 1 kHz haptic process (DESIGN.md §5, issue 4).
//
// A fixed-period loop on absolute deadlines (SCHED_FIFO and mlockall when permitted). Each step:
// read the device (scripted trajectory, simulated hand or external driver: --device), take the
// newest contact model from the receive thread (ModelMailbox: a swap, no lock), run
// device::HapticLoop (haptic step, safety, passivity observer), then publish DEVICE_STATE,
// DEVICE_FORCE and HAPTIC_STATE from buffers encoded in place. A receive thread decodes
// CONTACT_MODEL messages into the mailbox. At exit (script done, --duration reached,
// SIGINT/SIGTERM) it prints the loop statistics and, with
// --summary, writes them as JSON.

#include <atomic>
#include <cmath>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>
#include <vector>

#include "apps/commands.h"
#include "apps/haptic_inputs.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/realtime.h"
#include "core/scripted_trajectory.h"
#include "core/statistics.h"
#include "device/device_backend.h"
#include "device/haptic_loop.h"
#include "messages/adapters.h"
#include "messages/channels.h"
#include "messages/message_gate.h"
#include "messages/receive_thread.h"

namespace hapsim::apps {
namespace {

struct HapticCommandOptions {
  std::string scene_path;
  std::string device = "scripted";  // scripted | hand | external
  double wait_for_model_s = 10.0;   // 0: start the clock at once
  std::string lcm_url = messages::kDefaultLcmUrl;
  std::string mode;         // empty: the scene's haptic.mode
  double duration_s = 0.0;  // 0: the scene's script (time.num_steps · time.dt_s)
  std::string summary_path;
  std::string run_id;  // the run to serve (`hapsim run` passes its own)
};

// Decodes this run's CONTACT_MODEL messages into the mailbox; a message that is malformed, of
// another run, or fails validation never reaches it (the loop keeps the model it has).
class ModelReceiver {
 public:
  // lcp: each update's solver is prepared here, off the loop (PrepareLcpUpdate).
  ModelReceiver(device::ModelMailbox* mailbox, const config::Scene& scene,
                const device::HapticLoopOptions& options, messages::MessageGate* gate)
      : mailbox_(mailbox), scene_(scene), options_(options), gate_(gate) {}
  void Handle(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    if (!gate_->Admit(buffer, channel, &msg_)) return;
    device::ContactModelUpdate* slot = mailbox_->writer_slot();
    std::string error;
    if (!ReadContactModelUpdate(msg_, *scene_.tool, scene_.coupling, scene_.gravity_m_s2, options_,
                                slot, &error)) {
      gate_->CountRejected(channel,
                           "contact model " + std::to_string(msg_.sequence) + ": " + error);
      ++rejected_;
      return;
    }
    slot->ready_utime = WallMicros();
    mailbox_->Publish();
  }
  long rejected() const { return rejected_; }

 private:
  device::ModelMailbox* mailbox_;
  const config::Scene& scene_;
  device::HapticLoopOptions options_;
  messages::MessageGate* gate_;
  hapsim_lcm::contact_model_t msg_;  // reused: its vectors keep their storage between models
  long rejected_ = 0;
};

// Loop statistics, filled without allocation (buffers reserved for the whole run).
struct LoopStats {
  std::vector<double> period_error_s;  // |period − Δt| per step
  TimingHistogram period_histogram;    // the same, for the quantiles published every step
  double period_p50_s = 0.0, period_p99_s = 0.0;  // refreshed every 100 steps
  std::vector<double> compute_s;  // wall time of the step's work (before publishing)
  // Per model: from its publication to the start of the step that first used it (same-machine
  // wall clocks), s; and the part of it until the receive thread had it ready in the mailbox
  // (transport, decoding, lcp preparation). The rest is the wait for the next step, which is
  // uniform over one period for a model published at a random phase of the haptic clock.
  std::vector<double> model_latency_s;
  std::vector<double> model_ready_s;
  long overruns = 0, zeroed_steps = 0, passivity_alarms = 0, lcp_fallbacks = 0;
  LateStepCauses late;  // why the overruns were late
  // The slowest step's work and what its rows' solve did (hybrid and lcp modes).
  struct {
    double compute_s = 0.0;
    long step = -1;
    int rows = 0, iterations = 0, factorizations = 0;
    bool new_model = false;
  } slowest;
  double steal_ms = -1.0;  // the hypervisor's steal from all CPUs over the loop (-1: unknown)
  double max_force_sent_N = 0.0;
  // Fade-out when the models stop (the visual process died): the step the last model arrived,
  // the last step with a non-zero force, and the largest force sent with a stale model.
  long last_model_step = -1, last_nonzero_step = -1;
  long passivity_alarm_step = -1;  // the step the passivity observer first turned active
  double force_after_stale_N = 0.0;
};

// The step's period against Δt; the published quantiles are refreshed every 100 steps. No
// allocation: the vector is reserved for the run.
void RecordPeriod(long step, double period_s, double dt_s, LoopStats* stats) {
  if (step == 0) return;  // no period before the first step
  stats->period_error_s.push_back(std::abs(period_s - dt_s));
  stats->period_histogram.Add(std::abs(period_s - dt_s));
  if (step % 100 == 0) {
    stats->period_p50_s = stats->period_histogram.Quantile(0.5);
    stats->period_p99_s = stats->period_histogram.Quantile(0.99);
  }
}

// The step's work time (from its start to the force written), and what the slowest step's rows'
// solve did. No allocation: compute_s is reserved for the run.
void RecordCompute(long step, double compute_s, const device::HapticLoop& loop, bool new_model,
                   LoopStats* stats) {
  stats->compute_s.push_back(compute_s);
  if (compute_s <= stats->slowest.compute_s) return;
  const device::HapticStep& haptic_step = loop.haptic_step();
  stats->slowest = {compute_s,
                    step,
                    haptic_step.num_rows_in_use(),
                    haptic_step.rows_solver().last_iterations(),
                    haptic_step.rows_solver().last_num_factorizations(),
                    new_model};
}

// A step that ended more than a period after its deadline is an overrun, put down to its cause
// (LateStepCauses) from the thread's counters at its start and now. Times in ns, monotonic.
void RecordOverrun(std::int64_t deadline_ns, std::int64_t dt_ns, std::int64_t previous_end_ns,
                   std::int64_t start_ns, std::int64_t end_ns, const ThreadCounters& at_start,
                   LoopStats* stats) {
  if (end_ns <= deadline_ns + dt_ns) return;
  ++stats->overruns;
  stats->late.Add(previous_end_ns > deadline_ns, 1e-9 * (start_ns - deadline_ns),
                  1e-9 * (end_ns - start_ns), at_start, ReadThreadCounters(), 1e-9 * dt_ns);
}

// What the step did: the model it took (if any) and its latency, the force sent, the alarms.
void RecordStep(long step, std::int64_t step_start_utime, const device::ContactModelUpdate* update,
                const device::HapticLoopOutput& out, double model_stale_s, LoopStats* stats) {
  if (update != nullptr) {
    stats->last_model_step = step;
    if (stats->model_latency_s.size() < stats->model_latency_s.capacity()) {
      stats->model_latency_s.push_back(
          1e-6 * static_cast<double>(step_start_utime - update->published_utime));
      stats->model_ready_s.push_back(
          1e-6 * static_cast<double>(update->ready_utime - update->published_utime));
    }
  }
  if (out.sent.force_W_N.squaredNorm() > 0.0) stats->last_nonzero_step = step;
  if (out.model_age_s > model_stale_s)
    stats->force_after_stale_N = std::max(stats->force_after_stale_N, out.sent.force_W_N.norm());
  stats->zeroed_steps += out.sent.zeroed;
  stats->passivity_alarms += out.passivity_alarm;
  stats->lcp_fallbacks += out.lcp_fell_back;
  stats->max_force_sent_N = std::max(stats->max_force_sent_N, out.sent.force_W_N.norm());
  if (out.passivity_alarm) {  // once per run: the observer stays active
    stats->passivity_alarm_step = step;
    std::fprintf(stderr, "hapsim haptic: warning: passivity observer active at step %ld\n", step);
  }
}

// What one step read from the device.
struct DeviceReading {
  DeviceState state;
  double age_s = 0.0;
  long sequence = 0;
  bool in_process = true;  // scripted or simulated hand: this process publishes DEVICE_STATE
};

// The haptic tool's state in a HAPTIC_STATE (the visual process linearises the next model at it).
void FillHapticTool(const ToolState& tool, hapsim_lcm::haptic_state_t* state) {
  messages::PoseToMessage(tool, state->x_W_m, state->q_WT);
  for (int i = 0; i < 3; ++i) {
    state->v_W_m_s[i] = tool.v_W_m_s[i];
    state->L_W_kg_m2_s[i] = tool.L_W_kg_m2_s[i];
  }
}

// The messages the loop publishes every step, kept from step to step with their reason strings
// reserved, so that publishing allocates nothing (a zeroed step's reason is longer than the
// 15 characters std::string holds without the heap).
struct StepMessages {
  explicit StepMessages(std::int64_t run_id) {
    state.run_id = run_id;
    force.run_id = run_id;
    state.reason.reserve(64);
    force.reason.reserve(64);
    buffer.resize(1 << 16);
  }
  hapsim_lcm::haptic_state_t state{};
  hapsim_lcm::device_force_t force{};
  std::vector<std::uint8_t> buffer;  // encoding scratch
};

void PublishStep(lcm::LCM* lcm, std::int64_t run_id, long step, const DeviceReading& device,
                 const device::HapticLoop& loop, const device::HapticLoopOutput& out,
                 const LoopStats& stats, double period_s, StepMessages* messages_out) {
  const std::int64_t utime = WallMicros();
  std::vector<std::uint8_t>& buffer = messages_out->buffer;
  const auto publish = [&](const char* channel, const auto& msg) {
    const int size = msg.getEncodedSize();
    if (static_cast<int>(buffer.size()) < size) return;  // sized at start; never grows here
    msg.encode(buffer.data(), 0, size);
    lcm->publish(channel, buffer.data(), size);
  };
  if (device.in_process) {
    hapsim_lcm::device_state_t device_msg =
        messages::ToMessage(device.state, utime, device.sequence);
    device_msg.run_id = run_id;
    publish(messages::kDeviceStateChannel, device_msg);
  }
  const char* reason = out.sent.zeroed ? device::ToString(out.sent.state) : "";
  hapsim_lcm::haptic_state_t& state = messages_out->state;
  state.utime = utime;
  state.step = step;
  state.device_sequence = device.sequence;
  state.device_age_s = device.age_s;
  FillHapticTool(loop.tool_state(), &state);
  for (int i = 0; i < 3; ++i) {
    state.force_device_W_N[i] = out.sent.force_W_N[i];
    state.torque_device_W_N_m[i] = out.sent.torque_W_N_m[i];
    state.force_contact_W_N[i] = out.rendered.contact_force_W_N[i];
    state.torque_contact_W_N_m[i] = out.rendered.contact_torque_W_N_m[i];
  }
  state.model_sequence = out.model_sequence;
  state.model_age_s = std::isfinite(out.model_age_s) ? out.model_age_s : -1.0;
  state.period_s = period_s;
  state.period_error_p50_s = stats.period_p50_s;
  state.period_error_p99_s = stats.period_p99_s;
  state.period_error_max_s = stats.period_histogram.max_s();
  state.overruns = stats.overruns;
  state.zeroed = out.sent.zeroed;
  state.reason.assign(reason);
  state.passivity_energy_J = out.passivity_energy_J;
  publish(messages::kHapticStateChannel, state);
  hapsim_lcm::device_force_t& force = messages_out->force;
  force.utime = utime;
  force.sequence = device.sequence;
  for (int i = 0; i < 3; ++i) {
    force.force_W_N[i] = out.sent.force_W_N[i];
    force.torque_W_N_m[i] = out.sent.torque_W_N_m[i];
  }
  force.zeroed = out.sent.zeroed;
  force.reason.assign(reason);
  publish(messages::kDeviceForceChannel, force);
}

// Before its clock starts, the haptic process announces itself (HAPTIC_STATE with step −1, the
// initial tool; DEVICE_STATE with sequence −1 for an in-process device) every 10 ms until the
// first contact model arrives, so that model is in use from step 0 as in the in-process
// simulator, rather than after the visual process's first (slowest) frame. The mailbox is looked
// at every 0.1 ms (at the announcements only, the first model waited up to 10 ms). Returns the
// model; throws if none came within timeout_s.
const device::ContactModelUpdate* WaitForFirstModel(lcm::LCM* lcm, std::int64_t run_id,
                                                    device::ModelMailbox* mailbox,
                                                    const config::Scene& scene,
                                                    const device::HapticLoop& loop,
                                                    bool in_process_device, double timeout_s) {
  const std::int64_t give_up_ns = MonotonicNs() + std::llround(1e9 * timeout_s);
  const DeviceState device = ScriptedTrajectory(scene.trajectory).Sample(0.0);
  constexpr std::int64_t kAnnouncePeriodNs = 10000000, kPollPeriodNs = 100000;
  std::int64_t next_announcement_ns = MonotonicNs();
  while (!g_stop_requested.load()) {
    if (const device::ContactModelUpdate* model = mailbox->TakeNewest()) return model;
    if (MonotonicNs() < next_announcement_ns) {
      SleepUntil(MonotonicNs() + kPollPeriodNs);
      continue;
    }
    next_announcement_ns += kAnnouncePeriodNs;
    if (MonotonicNs() > give_up_ns)
      throw std::runtime_error("no contact model within " + std::to_string(timeout_s) +
                               " s: is `hapsim run` running on the same --lcm-url and --run-id?");
    const std::int64_t utime = WallMicros();
    if (in_process_device) {
      hapsim_lcm::device_state_t msg = messages::ToMessage(device, utime, -1);
      msg.run_id = run_id;
      lcm->publish(messages::kDeviceStateChannel, &msg);
    }
    hapsim_lcm::haptic_state_t state{};
    state.utime = utime;
    state.run_id = run_id;
    state.step = -1;
    state.device_sequence = -1;
    state.model_sequence = -1;
    state.model_age_s = -1.0;
    FillHapticTool(loop.tool_state(), &state);
    lcm->publish(messages::kHapticStateChannel, &state);
  }
  return nullptr;
}

nlohmann::json Summarize(LoopStats* stats, ModelReceiver* receiver,
                         const messages::MessageGate& gate, long steps, double dt_s,
                         double model_stale_s) {
  // The models stopped before the end (stale for the last model_stale_s or more): how long the
  // force took to reach zero after the last one arrived.
  const bool models_stopped =
      stats->last_model_step >= 0 && (steps - stats->last_model_step) * dt_s > model_stale_s;
  nlohmann::json fade = nullptr;
  if (models_stopped) fade = (stats->last_nonzero_step + 1 - stats->last_model_step) * dt_s;
  nlohmann::json period = {{"p50_us", 1e6 * Quantile(stats->period_error_s, 0.5)},
                           {"p99_us", 1e6 * Quantile(stats->period_error_s, 0.99)},
                           {"p999_us", 1e6 * Quantile(stats->period_error_s, 0.999)},
                           {"max_us", 1e6 * Quantile(stats->period_error_s, 1.0)}};
  const auto quantiles_ms = [](const std::vector<double>& s) {
    return nlohmann::json{{"p50_ms", 1e3 * Quantile(s, 0.5)},
                          {"p99_ms", 1e3 * Quantile(s, 0.99)},
                          {"max_ms", 1e3 * Quantile(s, 1.0)},
                          {"count", s.size()}};
  };
  return {{"steps", steps},
          {"dt_s", dt_s},
          {"period_error", period},
          {"compute_p50_us", 1e6 * Quantile(stats->compute_s, 0.5)},
          {"compute_max_us", 1e6 * Quantile(stats->compute_s, 1.0)},
          {"overruns", stats->overruns},
          {"overrun_causes",
           {{"preempted", stats->late.preempted},
            {"page_faults", stats->late.page_faults},
            {"blocked", stats->late.blocked},
            {"held_off_cpu", stats->late.held_off},
            {"held_off_cpu_ms", 1e3 * stats->late.held_off_s},
            {"catching_up", stats->late.catching_up},
            {"woke_late", stats->late.woke_late},
            {"own_work", stats->late.own_work}}},
          {"vm_steal_ms", stats->steal_ms},
          {"slowest_step",
           {{"step", stats->slowest.step},
            {"compute_us", 1e6 * stats->slowest.compute_s},
            {"new_model", stats->slowest.new_model},
            {"rows", stats->slowest.rows},
            {"iterations", stats->slowest.iterations},
            {"factorizations", stats->slowest.factorizations}}},
          {"zeroed_steps", stats->zeroed_steps},
          {"passivity_alarms", stats->passivity_alarms},
          {"lcp_fallback_steps", stats->lcp_fallbacks},
          {"max_force_sent_N", stats->max_force_sent_N},
          {"model_latency", quantiles_ms(stats->model_latency_s)},
          {"model_ready", quantiles_ms(stats->model_ready_s)},
          {"models_rejected", receiver->rejected()},
          {"messages_rejected", gate.num_rejected()},
          {"foreign_messages", gate.num_foreign()},
          {"first_foreign_run_id",
           gate.num_foreign() > 0 ? nlohmann::json(messages::FormatRunId(gate.first_foreign_run()))
                                  : nlohmann::json(nullptr)},
          {"run_id", messages::FormatRunId(gate.run_id())},
          {"model_stale_s", model_stale_s},
          {"fade_after_last_model_s", fade},
          {"force_after_stale_N", stats->force_after_stale_N}};
}

// The run's end on the console: timing, models, foreign and rejected messages, warnings.
void PrintSummary(const nlohmann::json& summary, const LoopStats& stats,
                  const messages::MessageGate& gate, long step,
                  const device::HapticLoopOptions& loop_options) {
  std::printf(
      "hapsim haptic: %ld steps; period error p50 %.1f us, p99 %.1f us, max %.1f us; "
      "%ld overruns; model latency (publish to first use) p50 %.2f ms, p99 %.2f ms "
      "(publish to ready p99 %.2f ms); max force sent %.3f N\n",
      step, summary["period_error"]["p50_us"].get<double>(),
      summary["period_error"]["p99_us"].get<double>(),
      summary["period_error"]["max_us"].get<double>(), stats.overruns,
      summary["model_latency"]["p50_ms"].get<double>(),
      summary["model_latency"]["p99_ms"].get<double>(),
      summary["model_ready"]["p99_ms"].get<double>(), stats.max_force_sent_N);
  if (stats.overruns > 0)
    std::printf(
        "hapsim haptic: overruns: %ld own work (slowest step %.2f ms), %ld catching up after "
        "them, %ld preempted, %ld page faults, %ld blocked, %ld held off the CPU (%.1f ms; the "
        "VM's steal over the loop %.0f ms), %ld woke late\n",
        stats.late.own_work, 1e3 * stats.slowest.compute_s, stats.late.catching_up,
        stats.late.preempted, stats.late.page_faults, stats.late.blocked, stats.late.held_off,
        1e3 * stats.late.held_off_s, stats.steal_ms, stats.late.woke_late);
  if (gate.num_foreign() > 0)
    std::printf(
        "hapsim haptic: ignored %ld messages of other runs on this LCM URL (first: run %s)\n",
        gate.num_foreign(), messages::FormatRunId(gate.first_foreign_run()).c_str());
  if (gate.num_rejected() > 0)
    std::printf("hapsim haptic: rejected %ld malformed or invalid messages (no force changed)\n",
                gate.num_rejected());
  if (stats.lcp_fallbacks > 0)  // as `hapsim sim` warns (sim_command.cc)
    std::fprintf(
        stderr,
        "hapsim haptic: warning: %ld of %ld steps rendered the linear model: their rows "
        "could not be solved (more than haptic.lcp_max_rows = %d, singular, or rejected)\n",
        stats.lcp_fallbacks, step, loop_options.lcp_max_rows);
  if (stats.passivity_alarm_step >= 0)
    std::fprintf(stderr,
                 "hapsim haptic: warning: the rendering generated energy from step %ld on "
                 "(passivity observer; HAPTIC_STATE.passivity_energy_J)\n",
                 stats.passivity_alarm_step);
  if (!summary["fade_after_last_model_s"].is_null())
    std::printf(
        "hapsim haptic: models stopped at step %ld; fade-out after the last model %.1f ms "
        "(stale threshold %.1f ms)\n",
        stats.last_model_step, 1e3 * summary["fade_after_last_model_s"].get<double>(),
        1e3 * loop_options.safety.model_stale_s);
}

// --device: the scripted trajectory, the simulated hand following it, or DEVICE_STATE messages
// from another process (subscribed here).
std::unique_ptr<device::DeviceBackend> MakeDeviceBackend(const std::string& device,
                                                         const config::Scene& scene, double dt_s,
                                                         messages::MessageGate* gate,
                                                         lcm::LCM* lcm) {
  if (device == "scripted")
    return std::make_unique<device::ScriptedDevice>(ScriptedTrajectory(scene.trajectory));
  if (device == "hand")
    return std::make_unique<device::SimulatedHand>(ScriptedTrajectory(scene.trajectory), scene.hand,
                                                   dt_s);
  auto external = std::make_unique<ExternalDevice>(gate);
  messages::KeepQueued(
      lcm->subscribe(messages::kDeviceStateChannel, &ExternalDevice::Handle, external.get()));
  return external;
}

void RunHaptic(const HapticCommandOptions& options) {
  std::int64_t run_id = 0;
  if (!messages::ParseRunId(options.run_id, &run_id))
    throw InputError("--run-id", 0, "",
                     "not 1-16 hex digits (and not 0): '" + options.run_id + "'");
  const config::Scene scene = config::LoadScene(options.scene_path);
  if (!scene.tool) throw InputError(scene.file, 0, "tool", "`hapsim haptic` needs a tool");
  const device::HapticMode mode =
      config::ResolveHapticMode(scene, options.mode, "--mode", /*allow_reference=*/false);
  const HapticWorld world = MakeHapticWorld(scene, mode);
  const device::HapticLoopOptions loop_options = MakeHapticLoopOptions(scene, mode, world);
  device::HapticLoop loop(scene.tool->model, scene.coupling, scene.gravity_m_s2,
                          scene.tool->initial_state, loop_options, world.body_model(),
                          world.objects);
  const double duration_s =
      options.duration_s > 0.0 ? options.duration_s : scene.num_steps * scene.dt_s;
  const long num_steps = std::lround(duration_s / loop_options.dt_s);

  lcm::LCM lcm(options.lcm_url);
  if (!lcm.good()) throw std::runtime_error("LCM: cannot open " + options.lcm_url);
  device::ModelMailbox mailbox;
  if (device::UsesContactRows(mode))
    for (device::ContactModelUpdate& slot : mailbox.slots_for_setup())
      device::EnsureLcpSolver(loop_options, &slot);
  messages::MessageGate gate("hapsim haptic", run_id);
  ModelReceiver receiver(&mailbox, scene, loop_options, &gate);
  messages::KeepQueued(
      lcm.subscribe(messages::kContactModelChannel, &ModelReceiver::Handle, &receiver));
  const std::unique_ptr<device::DeviceBackend> backend =
      MakeDeviceBackend(options.device, scene, loop_options.dt_s, &gate, &lcm);
  const bool in_process_device = options.device != "external";
  InstallStopHandlers();
  messages::ReceiveThread receive_thread(&lcm);
  const std::string rt_failure = RequestRealtime(80);
  if (!rt_failure.empty())
    std::fprintf(stderr, "hapsim haptic: warning: normal scheduling (%s)\n", rt_failure.c_str());
  std::printf("hapsim haptic: %s, mode %s, %ld steps at %g Hz on %s, run id %s\n",
              scene.name.c_str(), device::ToString(mode), num_steps, scene.haptic.rate_hz,
              options.lcm_url.c_str(), messages::FormatRunId(run_id).c_str());
  std::fflush(stdout);

  const device::ContactModelUpdate* first_model =
      options.wait_for_model_s > 0.0
          ? WaitForFirstModel(&lcm, run_id, &mailbox, scene, loop, in_process_device,
                              options.wait_for_model_s)
          : nullptr;
  if (first_model != nullptr) {
    std::printf("hapsim haptic: first contact model (frame %lld); the loop starts\n",
                static_cast<long long>(first_model->sequence));
    std::fflush(stdout);
  }

  LoopStats stats;
  stats.period_error_s.reserve(num_steps);
  stats.compute_s.reserve(num_steps);
  stats.model_latency_s.reserve(num_steps);
  stats.model_ready_s.reserve(num_steps);
  StepMessages step_messages(run_id);
  const std::int64_t dt_ns = std::llround(1e9 * loop_options.dt_s);
  std::int64_t deadline_ns = MonotonicNs() + dt_ns, previous_start_ns = 0, previous_end_ns = 0;
  long step = 0;
  const std::int64_t steal_before_ns = ReadStealNs();
  for (; step < num_steps && !g_stop_requested.load(); ++step) {
    SleepUntil(deadline_ns);
    const ThreadCounters counters_before = ReadThreadCounters();
    const std::int64_t start_ns = MonotonicNs();
    const std::int64_t step_start_utime = WallMicros();
    const double period_s = step == 0 ? loop_options.dt_s : 1e-9 * (start_ns - previous_start_ns);
    previous_start_ns = start_ns;
    RecordPeriod(step, period_s, loop_options.dt_s, &stats);
    DeviceReading device;
    device.in_process = in_process_device;
    device.state = backend->Read(step * loop_options.dt_s, &device.age_s, &device.sequence);
    const device::ContactModelUpdate* update =
        step == 0 && first_model != nullptr ? first_model : mailbox.TakeNewest();
    const device::HapticLoopOutput out = loop.Step(device.state, device.age_s, update);
    backend->Write(out.sent.force_W_N, out.sent.torque_W_N_m);
    RecordCompute(step, 1e-9 * (MonotonicNs() - start_ns), loop, update != nullptr, &stats);
    RecordStep(step, step_start_utime, update, out, loop_options.safety.model_stale_s, &stats);
    PublishStep(&lcm, run_id, step, device, loop, out, stats, period_s, &step_messages);
    const std::int64_t end_ns = MonotonicNs();
    RecordOverrun(deadline_ns, dt_ns, previous_end_ns, start_ns, end_ns, counters_before, &stats);
    previous_end_ns = end_ns;
    deadline_ns += dt_ns;
  }
  const std::int64_t steal_after_ns = ReadStealNs();
  if (steal_before_ns >= 0 && steal_after_ns >= 0)
    stats.steal_ms = 1e-6 * static_cast<double>(steal_after_ns - steal_before_ns);
  receive_thread.Stop();
  const nlohmann::json summary = Summarize(&stats, &receiver, gate, step, loop_options.dt_s,
                                           loop_options.safety.model_stale_s);
  PrintSummary(summary, stats, gate, step, loop_options);
  if (!options.summary_path.empty())
    WriteFileAtomically(options.summary_path,
                        [&](std::ostream& out) { out << summary.dump(2) << '\n'; });
}

}  // namespace

void AddHapticCommand(CLI::App* app) {
  auto options = std::make_shared<HapticCommandOptions>();
  CLI::App* haptic = app->add_subcommand(
      "haptic",
      "The 1 kHz haptic process: renders the contact models that `hapsim run` publishes over LCM\n"
      "to the scene's scripted device, with force and rate limits, zero force on stale or\n"
      "non-finite input, and a passivity observer. Usually spawned by `hapsim run`.");
  haptic->add_option("scene", options->scene_path, "Scene file (YAML) with a tool and a device")
      ->required();
  haptic->add_option("--lcm-url", options->lcm_url, "LCM provider URL")->capture_default_str();
  haptic->add_option("--mode", options->mode,
                     "hybrid, linear, lcp, coupling, penalty, material, impact or godobject\n"
                     "(default: the scene's haptic.mode, else hybrid); the visual process must\n"
                     "run the same mode");
  haptic
      ->add_option("--device", options->device,
                   "scripted (the scene's trajectory), hand (a simulated hand pulled along it,\n"
                   "closing the loop; the scene's device.hand), or external (a driver process\n"
                   "publishing DEVICE_STATE, see docs/DEVICE.md)")
      ->check(CLI::IsMember({"scripted", "hand", "external"}))
      ->capture_default_str();
  haptic
      ->add_option("--wait-for-model", options->wait_for_model_s,
                   "Seconds to wait for the first contact model before the clock starts\n"
                   "(0: start at once and render zero force until a model arrives)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  haptic
      ->add_option("--duration", options->duration_s,
                   "Seconds to run (default: the scene's time.num_steps * time.dt_s)")
      ->check(CLI::PositiveNumber);
  haptic
      ->add_option("--run-id", options->run_id,
                   "The run to serve, as `hapsim run` prints it (it passes its own when it\n"
                   "spawns this process); messages of any other run are ignored and counted")
      ->required();
  haptic->add_option("--summary", options->summary_path, "Write the loop statistics as JSON");
  haptic->callback([options] { RunHaptic(*options); });
}

}  // namespace hapsim::apps
