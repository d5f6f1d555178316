// `hapsim run SCENE`: the visual process of a two-process run (DESIGN.md §1, issue 4).
//
// It spawns `hapsim haptic SCENE` (unless --no-spawn) and follows its clock: visual frame k runs
// once the haptic process has published step k · (haptic steps per frame) − 1, with the newest
// device state and haptic tool state it published. Each frame publishes CONTACT_MODEL (the
// linear model linearised at the haptic tool, plus the rows in lcp mode) and SIM_FRAME (nodes,
// surface, tool, contacts, stage timings). The run stops when the script is done, at
// --duration, on SIGINT/SIGTERM (both processes shut down cleanly) or when the haptic process
// dies (a clear message and a non-zero exit). --log writes every channel to a standard LCM
// event log (a temporary name, renamed when the run ends).

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "apps/child_process.h"
#include "apps/commands.h"
#include "apps/grasp_report.h"
#include "apps/log_writer.h"
#include "apps/run_info.h"
#include "config/body_builder.h"
#include "config/scene.h"
#include "config/simulation_builder.h"
#include "contact/visual_frame.h"
#include "core/error.h"
#include "core/realtime.h"
#include "device/haptic_loop.h"
#include "fem/tet_mesh.h"
#include "messages/adapters.h"
#include "messages/channels.h"
#include "messages/message_gate.h"
#include "messages/receive_thread.h"

namespace hapsim::apps {
namespace {

struct RunCommandOptions {
  std::string scene_path;
  std::string lcm_url = messages::kDefaultLcmUrl;
  std::string mode;                 // empty: the scene's haptic.mode
  std::string device = "scripted";  // the haptic process's --device
  bool no_spawn = false;
  bool free_running = false;  // frames back to back instead of following the haptic clock
  double duration_s = 0.0;    // 0: the scene's script
  std::string log_path;
  std::string haptic_summary_path;  // passed to the spawned haptic process
  std::string run_id;               // empty: a random one
};

// The newest DEVICE_STATE and HAPTIC_STATE, and (with --log) every message to the log writer's
// queue. The two are not paired by HAPTIC_STATE.device_sequence on purpose: they feed different
// tools. The device drives the visual tool's coupling, where the freshest sample is the best
// one; the haptic tool's state is only the point the model is linearised at. (The in-process
// simulator gives frame k the device sample of step 30k, one newer than the one step 30k − 1
// used, so pairing would not bring the two runs closer either.) This process's own CONTACT_MODEL
// and SIM_FRAME reach the log the same way, back through multicast loopback: one path for every
// channel, stamped at reception as lcm-logger would, for the cost of copying ~250 kB a frame. Runs
// in the receive thread, which handles LCM continuously so that nothing is dropped while a visual
// frame computes or the disk stalls; the frame loop reads a consistent snapshot under the mutex
// (this process is not the real-time one).
class Listener {
 public:
  explicit Listener(std::int64_t run_id) : gate_("hapsim run", run_id) {}

  struct Snapshot {
    DeviceState device;
    ToolState haptic_tool;
    long haptic_step = -1;  // −1: the haptic process waits for the first model
  };

  void OnDevice(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    hapsim_lcm::device_state_t msg;
    if (!gate_.Admit(buffer, channel, &msg)) return;
    DeviceState device;
    std::string error;
    if (!messages::FromMessage(msg, &device, &error)) {
      gate_.CountRejected(channel, error);
      return;
    }
    if (!device.x_W_m.allFinite()) return;  // legal on the wire; the visual tool keeps the last
    std::lock_guard<std::mutex> lock(mutex_);
    latest_device_ = device;
    have_device_ = true;
  }
  void OnHaptic(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    hapsim_lcm::haptic_state_t msg;
    if (!gate_.Admit(buffer, channel, &msg)) return;
    ToolState tool;
    std::string error;
    if (!messages::HapticToolFromMessage(msg, &tool, &error)) {
      gate_.CountRejected(channel, error);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    snapshot_.haptic_tool = tool;
    snapshot_.haptic_step = msg.step;
    have_haptic_ = true;
  }
  // The log holds this run only: other runs' messages, and messages of types that are not
  // hapsim's, stay out (the typed handlers above count the other runs' traffic).
  void OnAny(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    std::int64_t run_id = 0;
    if (log_ && messages::PeekRunId(buffer->data, static_cast<int>(buffer->data_size), &run_id) &&
        run_id == gate_.run_id())
      log_->Add(buffer, channel);
  }
  void OpenLog(const std::string& path) { log_ = std::make_unique<LogWriter>(path); }
  void CloseLog() { log_.reset(); }
  const messages::MessageGate& gate() const { return gate_; }

  // The newest states, once both a device state and a haptic state have arrived.
  bool Get(Snapshot* snapshot) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!have_device_ || !have_haptic_) return false;
    *snapshot = snapshot_;
    snapshot->device = latest_device_;
    return true;
  }

 private:
  std::mutex mutex_;
  bool have_device_ = false, have_haptic_ = false;
  DeviceState latest_device_;
  Snapshot snapshot_;
  std::unique_ptr<LogWriter> log_;  // set before the receive thread starts, reset after it ends
  messages::MessageGate gate_;
};

pid_t SpawnHaptic(const RunCommandOptions& options) {
  std::vector<std::string> args = {"hapsim",        "haptic",   options.scene_path, "--lcm-url",
                                   options.lcm_url, "--run-id", options.run_id};
  if (!options.mode.empty()) args.insert(args.end(), {"--mode", options.mode});
  args.insert(args.end(), {"--device", options.device});
  if (options.duration_s > 0.0)
    args.insert(args.end(), {"--duration", std::to_string(options.duration_s)});
  if (!options.haptic_summary_path.empty())
    args.insert(args.end(), {"--summary", options.haptic_summary_path});
  return SpawnSelf(std::move(args), "the haptic process");
}

hapsim_lcm::sim_frame_t MakeSimFrame(const fem::State& body, const Matrix3Xi& surface,
                                     const ToolState& tool, const contact::VisualFrame& frame,
                                     const contact::VisualFrameStats& stats, long k, double t_s,
                                     std::int64_t run_id) {
  hapsim_lcm::sim_frame_t msg{};
  msg.utime = WallMicros();
  msg.run_id = run_id;
  msg.sequence = k;
  msg.t_s = t_s;
  msg.num_nodes = static_cast<int32_t>(body.x_m.size() / 3);
  msg.positions_W_m.assign(msg.num_nodes, std::vector<float>(3));
  for (int n = 0; n < msg.num_nodes; ++n)
    for (int d = 0; d < 3; ++d) msg.positions_W_m[n][d] = static_cast<float>(body.x_m[3 * n + d]);
  msg.num_triangles = static_cast<int32_t>(surface.cols());
  msg.triangles.assign(msg.num_triangles, std::vector<int32_t>(3));
  for (int f = 0; f < msg.num_triangles; ++f)
    for (int d = 0; d < 3; ++d) msg.triangles[f][d] = surface(d, f);
  messages::PoseToMessage(tool, msg.x_W_m, msg.q_WT);
  const auto& contacts = frame.contacts();
  const int rows_per_contact = frame.jacobian().rows_per_contact;
  msg.num_contacts = static_cast<int32_t>(contacts.size());
  msg.p_W_m.assign(msg.num_contacts, std::vector<double>(3));
  msg.n_W.assign(msg.num_contacts, std::vector<double>(3));
  msg.lambda_N.resize(msg.num_contacts);
  for (int i = 0; i < msg.num_contacts; ++i) {
    for (int d = 0; d < 3; ++d) {
      msg.p_W_m[i][d] = contacts[i].p_body_W_m[d];
      msg.n_W[i][d] = contacts[i].n_W[d];
    }
    msg.lambda_N[i] = frame.impulses()[rows_per_contact * i];
  }
  msg.time_coupling_s = stats.coupling_s;
  msg.time_free_tool_s = stats.free_tool_s;
  msg.time_free_fem_s = stats.free_fem_s;
  msg.time_detection_s = stats.detection_s;
  msg.time_response_s = stats.response_s;
  msg.time_model_s = stats.model_s;
  msg.time_sanity_s = stats.sanity_s;
  msg.time_total_s = stats.total_s;
  msg.contact_kind.resize(msg.num_contacts);
  for (int i = 0; i < msg.num_contacts; ++i)
    msg.contact_kind[i] = static_cast<int8_t>(contact::KindOf(contacts[i]));
  msg.num_objects = frame.num_objects();
  msg.object_x_W_m.assign(msg.num_objects, std::vector<double>(3));
  msg.object_q_WO.assign(msg.num_objects, std::vector<double>(4));
  for (int i = 0; i < msg.num_objects; ++i) {
    const Eigen::Isometry3d& X_WO = frame.object_pose(i);
    const Eigen::Quaterniond q_WO(X_WO.linear());
    for (int d = 0; d < 3; ++d) msg.object_x_W_m[i][d] = X_WO.translation()[d];
    const double q[4] = {q_WO.w(), q_WO.x(), q_WO.y(), q_WO.z()};
    for (int d = 0; d < 4; ++d) msg.object_q_WO[i][d] = q[d];
  }
  msg.selected_object = frame.selected_object();
  msg.grabbed_object = frame.grabbed_object();
  if (frame.grasp() != nullptr) msg.grasped_nodes = frame.grasp()->held_nodes();
  msg.num_grasped = static_cast<int32_t>(msg.grasped_nodes.size());
  msg.num_grasp_slipped = stats.num_grasp_slipped;
  return msg;
}

// Visual frames slaved to the haptic clock; returns the number of frames run.
// The haptic process is spawned (unless --no-spawn) only once the body and the frame are built,
// so that its clock starts when the first model can follow within one frame's computation.
long RunFrames(const config::Scene& scene, device::HapticMode mode,
               const RunCommandOptions& options, const hapsim_lcm::run_info_t& info, lcm::LCM* lcm,
               Listener* listener, pid_t* child, int* child_code, std::string* child_end) {
  const std::optional<config::Body> body = config::MakeSceneBody(scene);
  const contact::VisualFrameOptions visual = device::SetUpFrameForMode(
      config::MakeVisualFrameOptions(scene), mode, scene.dt_s, 1.0 / scene.haptic.rate_hz);
  // coupling: there is no haptic tool; the model is linearised at the visual tool (and unused).
  // godobject: the visual tool is coupled to the device, to press the body (as in `hapsim sim`).
  const bool haptic_tool =
      mode != device::HapticMode::kCoupling && mode != device::HapticMode::kGodObject;
  // The geometric modes and godobject render the frame's world: it travels with each model.
  const bool send_world = device::NeedsWorld(mode);
  std::vector<Eigen::Isometry3d> object_poses;
  contact::VisualFrame frame = config::MakeVisualFrame(scene, body, visual);
  // A scene of rigid objects: no body state, no surface (SIM_FRAME has no nodes).
  fem::State body_state = body ? fem::MakeRestState(body->model) : fem::State{};
  ToolState visual_tool = scene.tool->initial_state;
  const Matrix3Xi surface = body ? fem::ExtractBoundarySurface(body->model.mesh) : Matrix3Xi();
  *child = options.no_spawn ? -1 : SpawnHaptic(options);
  const double duration_s =
      options.duration_s > 0.0 ? options.duration_s : scene.num_steps * scene.dt_s;
  const long num_frames = std::lround(duration_s / scene.dt_s);
  const int steps_per_frame = scene.haptic.steps_per_frame;
  // RUN_INFO again about every second, for subscribers and loggers that started late.
  const long frames_per_run_info = std::max(1L, std::lround(1.0 / scene.dt_s));
  long k = 0;
  for (; k < num_frames && !g_stop_requested.load(); ++k) {
    // Wait for the haptic clock to reach the frame: frame k needs the state after step
    // k·steps_per_frame − 1 (frame 0: the announcement of a haptic process waiting, step −1).
    // Free-running: any state will do, so frames follow each other as fast as they compute.
    Listener::Snapshot now;
    const long needed_step = options.free_running ? -1 : k * steps_per_frame - 1;
    while (!g_stop_requested.load() && !(listener->Get(&now) && now.haptic_step >= needed_step)) {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      *child_end = CheckChild(*child, child_code);
      if (!child_end->empty()) return k;
    }
    if (g_stop_requested.load()) break;
    if (k > 0 && k % frames_per_run_info == 0) lcm->publish(messages::kRunInfoChannel, &info);
    const contact::VisualFrameStats stats =
        frame.Step(now.device, &body_state, &visual_tool, haptic_tool ? &now.haptic_tool : nullptr);
    messages::ContactModelHeader header;
    header.utime = WallMicros();
    header.sequence = k;
    header.dt_visual_s = scene.dt_s;
    header.dt_haptic_s = visual.haptic_dt_s;
    header.t_frame_s = (k + 1) * scene.dt_s;
    header.x_W_m = now.haptic_tool.x_W_m;
    header.q_WT = now.haptic_tool.q_WT;
    header.visual_tool = visual_tool;
    hapsim_lcm::contact_model_t model_msg = messages::ToMessage(
        frame.linear_model(), visual.export_contact_rows ? &frame.contact_rows() : nullptr, header);
    model_msg.run_id = info.run_id;
    if (send_world) {
      object_poses.resize(frame.num_objects());
      for (int i = 0; i < frame.num_objects(); ++i) object_poses[i] = frame.object_pose(i);
      messages::WorldToMessage(body_state.x_m, object_poses, &model_msg);
    }
    lcm->publish(messages::kContactModelChannel, &model_msg);
    const hapsim_lcm::sim_frame_t sim_frame = MakeSimFrame(body_state, surface, visual_tool, frame,
                                                           stats, k, k * scene.dt_s, info.run_id);
    lcm->publish(messages::kSimFrameChannel, &sim_frame);
    const std::string grasp = DescribeGraspEvents(scene, k * scene.dt_s, stats);
    if (!grasp.empty()) std::fprintf(stderr, "hapsim run: %s\n", grasp.c_str());
  }
  return k;
}

int RunVisual(RunCommandOptions options) {
  std::int64_t run_id = 0;
  if (options.run_id.empty()) {
    run_id = messages::MakeRunId();
    options.run_id = messages::FormatRunId(run_id);
  } else if (!messages::ParseRunId(options.run_id, &run_id)) {
    throw InputError("--run-id", 0, "",
                     "not 1-16 hex digits (and not 0): '" + options.run_id + "'");
  }
  const config::Scene scene = config::LoadScene(options.scene_path);
  if (!scene.tool) throw InputError(scene.file, 0, "tool", "`hapsim run` needs a tool");
  const device::HapticMode mode =
      config::ResolveHapticMode(scene, options.mode, "--mode", /*allow_reference=*/false);
  lcm::LCM lcm(options.lcm_url);
  if (!lcm.good()) throw std::runtime_error("LCM: cannot open " + options.lcm_url);
  const hapsim_lcm::run_info_t info = MakeRunInfo(scene, device::ToString(mode), run_id);
  Listener listener(run_id);
  messages::KeepQueued(
      lcm.subscribe(messages::kDeviceStateChannel, &Listener::OnDevice, &listener));
  messages::KeepQueued(
      lcm.subscribe(messages::kHapticStateChannel, &Listener::OnHaptic, &listener));
  const std::string log_tmp = options.log_path + ".tmp";
  if (!options.log_path.empty()) {
    listener.OpenLog(log_tmp);
    messages::KeepQueued(lcm.subscribe(".*", &Listener::OnAny, &listener));
  }
  InstallStopHandlers();
  messages::ReceiveThread receive_thread(&lcm);
  std::printf("hapsim run: run id %s on %s%s\n", options.run_id.c_str(), options.lcm_url.c_str(),
              options.no_spawn
                  ? (" (start the haptic process with --run-id " + options.run_id + ")").c_str()
                  : "");
  std::fflush(stdout);
  lcm.publish(messages::kRunInfoChannel, &info);
  pid_t child = -1;
  int child_code = 0;
  std::string child_end;
  const long frames =
      RunFrames(scene, mode, options, info, &lcm, &listener, &child, &child_code, &child_end);
  // Shutdown: the haptic process ends its script by itself; on a stop request it gets SIGTERM.
  if (child > 0 && child_end.empty()) {
    if (g_stop_requested.load()) kill(child, SIGTERM);
    for (int waited_ms = 0; child_end.empty() && waited_ms < 5000; waited_ms += 5) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      child_end = CheckChild(child, &child_code);
    }
    if (child_end.empty()) {
      kill(child, SIGKILL);
      waitpid(child, nullptr, 0);  // reap it
      child_end = "did not stop within 5 s and was killed";
      child_code = 1;
    }
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the last messages in flight
  receive_thread.Stop();
  if (!options.log_path.empty()) {
    listener.CloseLog();
    std::filesystem::rename(log_tmp, options.log_path);
  }
  std::printf("hapsim run: %ld visual frames; haptic process %s\n", frames,
              child > 0 ? child_end.c_str() : "not spawned");
  const messages::MessageGate& gate = listener.gate();
  if (gate.num_foreign() > 0)
    std::printf("  ignored %ld messages of other runs on this LCM URL (first: run %s)\n",
                gate.num_foreign(), messages::FormatRunId(gate.first_foreign_run()).c_str());
  if (gate.num_rejected() > 0)
    std::printf("  rejected %ld malformed or invalid messages\n", gate.num_rejected());
  if (!options.log_path.empty()) std::printf("  wrote %s\n", options.log_path.c_str());
  if (child > 0 && child_code != 0) {
    std::fprintf(stderr, "hapsim run: error: the haptic process %s\n", child_end.c_str());
    return 1;
  }
  return g_stop_requested.load() ? 130 : 0;
}

}  // namespace

void AddRunCommand(CLI::App* app) {
  auto options = std::make_shared<RunCommandOptions>();
  CLI::App* run = app->add_subcommand(
      "run",
      "Two-process run: this visual process (FEM, contact, linear contact model) publishes\n"
      "models over LCM to `hapsim haptic`, which it spawns and supervises, at 1 kHz.");
  run->add_option("scene", options->scene_path, "Scene file (YAML) with body, tool and device")
      ->required();
  run->add_option("--lcm-url", options->lcm_url, "LCM provider URL")->capture_default_str();
  run->add_option("--mode", options->mode,
                  "hybrid (the paper's linear model, and the frame's other candidate rows\n"
                  "switched on at 1 kHz so a fast tool cannot pass), linear (the paper's model\n"
                  "alone), lcp (1 kHz unilateral solve on the frame's rows), coupling (standard\n"
                  "multirate), or the source papers' 1 kHz methods on the frame's world:\n"
                  "penalty, material, impact, godobject (a point tool; see\n"
                  "docs/HAPTIC_MODES.md); default: the scene's haptic.mode, else hybrid");
  run->add_option("--device", options->device,
                  "The haptic process's device: scripted, hand or external (docs/DEVICE.md)")
      ->check(CLI::IsMember({"scripted", "hand", "external"}))
      ->capture_default_str();
  run->add_flag("--free-running", options->free_running,
                "Run visual frames back to back (as fast as they compute) instead of at the\n"
                "scene's rate on the haptic clock; each uses the newest haptic state");
  run->add_flag("--no-spawn", options->no_spawn,
                "Do not start `hapsim haptic` (run it yourself, e.g. on the device's machine)");
  run->add_option("--duration", options->duration_s,
                  "Seconds of simulated time (default: the scene's script)")
      ->check(CLI::PositiveNumber);
  run->add_option("--log", options->log_path, "Write every channel to this LCM event log");
  run->add_option("--run-id", options->run_id,
                  "This run's identity, 1-16 hex digits (default: random). Every message carries\n"
                  "it and each process ignores other runs' messages, so runs can share a URL;\n"
                  "with --no-spawn, start `hapsim haptic --run-id` with the same id");
  run->add_option("--haptic-summary", options->haptic_summary_path,
                  "Have the haptic process write its loop statistics to this JSON file");
  run->callback([options] {
    const int code = RunVisual(*options);
    if (code != 0) throw RunExit{code};
  });
}

}  // namespace hapsim::apps
