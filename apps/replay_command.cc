// `hapsim replay LOG`: re-runs the haptic loop (device::HapticLoop) from an LCM event log of a
// `hapsim run` and checks that it reproduces every logged device force bit for bit, or reports
// the first step that differs (issue 4). The inputs of each step are in the log: the device state
// (DEVICE_STATE, sequence = step), the contact model in use (HAPTIC_STATE.model_sequence: a new
// model is applied at the first step that names it; its CONTACT_MODEL message by sequence) and
// the scene (RUN_INFO's own text, its input files checked against their hashes; or --scene).
// A log holds one run (`hapsim run --log`) or several (lcm-logger beside two runs): replay takes
// the messages of one run, the only one or --run-id. --csv exports the logged haptic steps;
// --republish [--speed X] plays the log to LCM for viewers instead. A truncated or corrupt log,
// or a message in it that does not decode, is an error naming the byte or the event.

#include <cstdio>
#include <filesystem>
#include <iterator>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include "apps/commands.h"
#include "apps/haptic_inputs.h"
#include "apps/run_info.h"
#include "config/scene.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/realtime.h"
#include "device/haptic_loop.h"
#include "messages/adapters.h"
#include "messages/channels.h"
#include "messages/lcm_log_reader.h"
#include "messages/logged_run.h"
#include "messages/message_gate.h"

namespace hapsim::apps {
namespace {

struct ReplayOptions {
  std::string log_path;
  std::string scene_path;  // empty: RUN_INFO's
  std::string csv_path;
  bool republish = false;  // play the log to LCM instead of re-running the loop
  double speed = 1.0;
  std::string lcm_url = messages::kDefaultLcmUrl;
  std::string run_id;  // empty: the log's only run
};

// Publishes every event of the log on its channel, at its logged time scaled by 1/speed (for
// viewers such as lcm-spy). Returns the number of events played.
long Republish(const ReplayOptions& options) {
  messages::LcmLogReader log(options.log_path);
  messages::LcmLogEvent event;
  lcm::LCM lcm(options.lcm_url);
  if (!lcm.good()) throw std::runtime_error("LCM: cannot open " + options.lcm_url);
  InstallStopHandlers();
  long played = 0;
  std::int64_t first_utime = -1, start_ns = MonotonicNs();
  while (log.Next(&event)) {
    if (g_stop_requested.load()) break;
    if (first_utime < 0) first_utime = event.timestamp_us;
    SleepUntil(start_ns + std::llround(1e3 * static_cast<double>(event.timestamp_us - first_utime) /
                                       options.speed));
    lcm.publish(event.channel, event.data.data(), static_cast<unsigned>(event.data.size()));
    ++played;
  }
  return played;
}

struct LogContents {
  std::int64_t run_id = 0;
  std::optional<hapsim_lcm::run_info_t> info;        // the run's RUN_INFO (the last of its copies)
  std::string mode;                                  // RUN_INFO.mode: the haptic process's
  std::map<long, hapsim_lcm::haptic_state_t> steps;  // by step
  std::map<long, DeviceState> devices;               // by sequence
  std::vector<hapsim_lcm::contact_model_t> model_messages;  // decoded in Replay (needs the scene)
  long skipped = 0;  // messages of the run that do not decode or validate (the live side's too)
};

// Decodes a logged message of the run. One that does not decode was rejected by the live process
// too (a hostile or broken publisher using the run's id), so it is skipped and counted, with the
// first one named, rather than ending the replay.
template <typename Message>
bool DecodeEvent(const messages::LcmLogEvent& event, const std::string& log_path, Message* msg,
                 LogContents* contents) {
  std::string error;
  if (messages::Decode(event.data.data(), static_cast<int>(event.data.size()), msg, &error))
    return true;
  if (contents->skipped++ == 0)
    std::fprintf(stderr, "hapsim replay: warning: %s: skipping event %ld at byte %ld on %s: %s\n",
                 log_path.c_str(), static_cast<long>(event.event_number),
                 static_cast<long>(event.offset), event.channel.c_str(), error.c_str());
  return false;
}

// Reads the log twice: once for the run to replay (ChooseLoggedRun), then its messages. Other
// runs' messages are left alone.
LogContents ReadLog(const std::string& path, const std::string& requested_run) {
  LogContents contents;
  contents.run_id = messages::ChooseLoggedRun(path, requested_run);
  messages::LcmLogEvent event;
  messages::LcmLogReader log(path);
  while (log.Next(&event)) {
    std::int64_t run_id = 0;
    if (!messages::PeekRunId(event.data.data(), static_cast<int>(event.data.size()), &run_id) ||
        run_id != contents.run_id)
      continue;
    const std::string& channel = event.channel;
    if (channel == messages::kRunInfoChannel) {
      hapsim_lcm::run_info_t info;
      if (!DecodeEvent(event, path, &info, &contents)) continue;
      contents.mode = info.mode;
      contents.info = std::move(info);
    } else if (channel == messages::kDeviceStateChannel) {
      hapsim_lcm::device_state_t msg;
      if (DecodeEvent(event, path, &msg, &contents))
        contents.devices[msg.sequence] = ReadDeviceState(msg);
    } else if (channel == messages::kHapticStateChannel) {
      hapsim_lcm::haptic_state_t msg;
      // step −1: the haptic process waiting for the first model
      if (DecodeEvent(event, path, &msg, &contents) && msg.step >= 0)
        contents.steps[msg.step] = msg;
    } else if (channel == messages::kContactModelChannel) {
      hapsim_lcm::contact_model_t msg;
      if (DecodeEvent(event, path, &msg, &contents))
        contents.model_messages.push_back(std::move(msg));
    }
  }
  if (contents.steps.empty()) throw InputError(path, 0, "", "no haptic steps in the log");
  return contents;
}

void WriteCsv(const std::string& path, const LogContents& log) {
  WriteFileAtomically(path, [&](std::ostream& out) {
    out << "step,force_x_N,force_y_N,force_z_N,torque_x_N_m,torque_y_N_m,torque_z_N_m,tool_x_m,"
           "tool_y_m,tool_z_m,model_sequence,model_age_s,zeroed,passivity_energy_J\n";
    out.precision(17);
    for (const auto& [step, s] : log.steps) {
      out << step << ',' << s.force_device_W_N[0] << ',' << s.force_device_W_N[1] << ','
          << s.force_device_W_N[2] << ',' << s.torque_device_W_N_m[0] << ','
          << s.torque_device_W_N_m[1] << ',' << s.torque_device_W_N_m[2] << ',' << s.x_W_m[0] << ','
          << s.x_W_m[1] << ',' << s.x_W_m[2] << ',' << s.model_sequence << ',' << s.model_age_s
          << ',' << s.zeroed << ',' << s.passivity_energy_J << '\n';
    }
  });
}

// The inputs of a step whose HAPTIC_STATE was lost in transport, when they follow from its logged
// neighbours without doubt: an in-process device (its state's sequence is the step, age 0) and the
// same contact model before and after the gap (a model switch inside a gap cannot be placed).
// Its device state must be in the log. Returns false otherwise.
bool RecreateMissingStep(const LogContents& log, long step, hapsim_lcm::haptic_state_t* state) {
  const auto after = log.steps.upper_bound(step);
  if (after == log.steps.begin() || after == log.steps.end()) return false;
  const auto before = std::prev(log.steps.lower_bound(step));
  const hapsim_lcm::haptic_state_t& a = before->second;
  const hapsim_lcm::haptic_state_t& b = after->second;
  const bool in_process = a.device_sequence == before->first && b.device_sequence == after->first &&
                          a.device_age_s == 0.0 && b.device_age_s == 0.0;
  if (!in_process || a.model_sequence != b.model_sequence || !log.devices.count(step)) return false;
  *state = a;
  state->step = step;
  state->device_sequence = step;
  return true;
}

// Re-runs the loop; returns the number of steps compared, or throws at the first difference
// (steps lost from the log are re-run when RecreateMissingStep can, and not compared).
long Replay(const config::Scene& scene, LogContents* log_contents) {
  const LogContents& log = *log_contents;
  device::HapticMode mode = scene.haptic.mode;
  if (const auto logged_mode = config::ParseHapticMode(log.mode)) mode = *logged_mode;
  const HapticWorld world = MakeHapticWorld(scene, mode);
  const device::HapticLoopOptions options = MakeHapticLoopOptions(scene, mode, world);
  device::HapticLoop loop(scene.tool->model, scene.coupling, scene.gravity_m_s2,
                          scene.tool->initial_state, options, world.body_model(), world.objects);
  // As the haptic process's receive thread did (apps/haptic_inputs.h): the same inputs.
  std::map<long, std::unique_ptr<device::ContactModelUpdate>> models;  // by sequence
  for (const hapsim_lcm::contact_model_t& msg : log.model_messages) {
    auto update = std::make_unique<device::ContactModelUpdate>();
    std::string error;
    // One the live process rejected (ModelReceiver) is skipped likewise; a step that names it
    // fails below.
    if (!ReadContactModelUpdate(msg, *scene.tool, scene.coupling, scene.gravity_m_s2, options,
                                update.get(), &error)) {
      if (log_contents->skipped++ == 0)
        std::fprintf(stderr, "hapsim replay: warning: skipping contact model %ld: %s\n",
                     static_cast<long>(msg.sequence), error.c_str());
      continue;
    }
    models[msg.sequence] = std::move(update);
  }
  long compared = 0;
  long recreated = 0;
  std::int64_t model_in_use = -1;
  const long first_step = log.steps.begin()->first, last_step = log.steps.rbegin()->first;
  for (long step = first_step; step <= last_step; ++step) {
    const auto found_step = log.steps.find(step);
    const bool was_logged = found_step != log.steps.end();
    hapsim_lcm::haptic_state_t logged;
    if (was_logged) {
      logged = found_step->second;
    } else if (!RecreateMissingStep(log, step, &logged)) {
      throw std::runtime_error("the log misses the haptic state of step " + std::to_string(step));
    } else {
      ++recreated;
    }
    // A negative sequence: no device state had arrived (an external driver not yet started); the
    // live loop was given an invalid state then.
    const auto found_device = log.devices.find(logged.device_sequence);
    if (logged.device_sequence >= 0 && found_device == log.devices.end())
      throw std::runtime_error("step " + std::to_string(step) + " used device state " +
                               std::to_string(logged.device_sequence) +
                               ", which is not in the log");
    const DeviceState device =
        logged.device_sequence >= 0 ? found_device->second : MakeInvalidDeviceState();
    const device::ContactModelUpdate* update = nullptr;
    if (logged.model_sequence != model_in_use) {
      const auto found = models.find(logged.model_sequence);
      if (found == models.end())
        throw std::runtime_error("step " + std::to_string(step) + " used contact model " +
                                 std::to_string(logged.model_sequence) +
                                 ", which is not in the log");
      update = found->second.get();
      model_in_use = logged.model_sequence;
    }
    const device::HapticLoopOutput out = loop.Step(device, logged.device_age_s, update);
    if (!was_logged) continue;  // nothing to compare with
    for (int i = 0; i < 3; ++i) {
      if (out.sent.force_W_N[i] != logged.force_device_W_N[i] ||
          out.sent.torque_W_N_m[i] != logged.torque_device_W_N_m[i]) {
        char message[256];
        std::snprintf(message, sizeof(message),
                      "step %ld differs: replayed force (%.17g, %.17g, %.17g) N, logged (%.17g, "
                      "%.17g, %.17g) N",
                      step, out.sent.force_W_N.x(), out.sent.force_W_N.y(), out.sent.force_W_N.z(),
                      logged.force_device_W_N[0], logged.force_device_W_N[1],
                      logged.force_device_W_N[2]);
        throw std::runtime_error(message);
      }
    }
    ++compared;
  }
  if (recreated > 0)
    std::printf(
        "hapsim replay: %ld haptic steps missing from the log (lost datagrams) were "
        "re-created from their neighbours\n",
        recreated);
  return compared;
}

// The scene to replay with: --scene, else the log's own (LoadLoggedScene checks its input files).
config::Scene ReplayScene(const ReplayOptions& options, const LogContents& log) {
  if (!options.scene_path.empty()) return config::LoadScene(options.scene_path);
  if (!log.info)
    throw InputError(options.log_path, 0, "RUN_INFO",
                     "no RUN_INFO of the run in the log; give --scene");
  if (log.info->scene_yaml.empty())
    throw InputError(options.log_path, 0, "RUN_INFO",
                     "the run's RUN_INFO carries no scene text (an older log); give --scene");
  return LoadLoggedScene(*log.info, options.log_path);
}

void RunReplay(const ReplayOptions& options) {
  if (options.republish) {
    // A truncated or corrupt log is an error before anything is sent.
    messages::LcmLogEvent event;
    for (messages::LcmLogReader log(options.log_path); log.Next(&event);) {
    }
    const long played = Republish(options);
    std::printf("hapsim replay: published %ld events of %s at %gx on %s\n", played,
                options.log_path.c_str(), options.speed, options.lcm_url.c_str());
    return;
  }
  LogContents log = ReadLog(options.log_path, options.run_id);
  if (!options.csv_path.empty()) WriteCsv(options.csv_path, log);
  const config::Scene scene = ReplayScene(options, log);
  if (!scene.tool) throw InputError(scene.file, 0, "tool", "the scene has no tool");
  const long compared = Replay(scene, &log);
  if (log.skipped > 0)
    std::printf(
        "hapsim replay: skipped %ld messages of the run that do not decode or validate "
        "(the live processes rejected them too)\n",
        log.skipped);
  std::printf(
      "hapsim replay: %ld haptic steps of %s reproduced bit for bit (%zu contact models; "
      "run %s, scene %s)\n",
      compared, options.log_path.c_str(), log.model_messages.size(),
      messages::FormatRunId(log.run_id).c_str(),
      options.scene_path.empty() ? "from the log" : options.scene_path.c_str());
  if (!options.csv_path.empty()) std::printf("  wrote %s\n", options.csv_path.c_str());
}

}  // namespace

void AddReplayCommand(CLI::App* app) {
  auto options = std::make_shared<ReplayOptions>();
  CLI::App* replay = app->add_subcommand(
      "replay",
      "Re-runs the haptic loop from an LCM log of `hapsim run` (its device states and contact\n"
      "models) and checks that every logged device force is reproduced bit for bit.");
  replay->add_option("log", options->log_path, "LCM event log (hapsim run --log, lcm-logger)")
      ->required();
  replay->add_option("--scene", options->scene_path,
                     "Scene file (default: the scene text the log carries, after checking that\n"
                     "the mesh and tool files it reads are unchanged)");
  replay->add_option("--run-id", options->run_id,
                     "The run to replay when the log holds several (lcm-logger beside two runs)");
  replay->add_option("--csv", options->csv_path, "Export the logged haptic steps as CSV");
  replay->add_flag("--republish", options->republish,
                   "Play the log to LCM (every channel, logged timing) for viewers, instead of\n"
                   "re-running the haptic loop");
  replay->add_option("--speed", options->speed, "Playback speed factor for --republish")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  replay->add_option("--lcm-url", options->lcm_url, "LCM provider URL for --republish")
      ->capture_default_str();
  replay->callback([options] { RunReplay(*options); });
}

}  // namespace hapsim::apps
