// `hapsim view [LOG]`: the 3D viewer (OpenCV viz, i.e. VTK). With a log it plays the logged run
// (keys: space pause, . and , a frame forward and back, ] and [ a second, up and down the speed,
// Home the start, q quit); without one it shows the run live over LCM from SIM_FRAME, HAPTIC_STATE
// and DEVICE_STATE, the scene taken from the run's RUN_INFO. Headless (under Xvfb):
// --screenshot FILE.png [--at S] and --video FILE.avi.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "apps/commands.h"
#include "apps/live_run.h"
#include "apps/palpation_score.h"
#include "apps/realtime.h"
#include "apps/receive_thread.h"
#include "apps/run_info.h"
#include "apps/run_timeline.h"
#include "apps/view_window.h"
#include "config/scene.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "messages/channels.h"

namespace hapsim::apps {
namespace {

struct ViewOptions {
  std::string log_path;  // empty: live
  std::string lcm_url = messages::kDefaultLcmUrl;
  std::string run_id;
  std::string scene_path;  // overrides the logged scene
  double at_s = -1.0;      // screenshot time; < 0: the last frame (log), the first (live)
  std::string screenshot_path;
  std::string video_path;
  double fps = 30.0;
  double speed = 1.0;
  std::string size = "1024x768";
  double wait_s = 30.0;               // live: for the run to be heard
  double duration_s = 0.0;            // live video: seconds to record (0: until the run ends)
  double displacement_from_s = -1.0;  // colour displacements from the frame at this time; < 0: rest
  std::string score_path;             // a log: score the scene's task, write it here and exit
  PainterOptions painter;
};

// Playback of a logged run, driven by keys.
struct Player {
  double t_s = 0.0, first_s = 0.0, last_s = 0.0, frame_s = 0.0;
  double speed = 1.0;
  bool paused = false;

  void OnKey(const std::string& key) {
    if (key == "space") paused = !paused;
    if (key == "period") Seek(frame_s);
    if (key == "comma") Seek(-frame_s);
    if (key == "bracketright") Seek(1.0);
    if (key == "bracketleft") Seek(-1.0);
    if (key == "Up") speed = std::min(speed * 2.0, 16.0);
    if (key == "Down") speed = std::max(speed / 2.0, 1.0 / 16.0);
    if (key == "Home") Seek(first_s - t_s);
    // Echoed on the terminal too, so that a scripted session can follow it.
    std::printf("hapsim view: key %s: %s\n", key.c_str(), Status().c_str());
    std::fflush(stdout);
  }
  void Seek(double delta_s) {
    paused = true;
    t_s = std::clamp(t_s + delta_s, first_s, last_s);
  }
  std::string Status() const {
    char text[200];
    std::snprintf(text, sizeof(text),
                  "log %.2f / %.2f s  %s x%g   (space pause, , . frame, [ ] second, up down speed)",
                  t_s, last_s, paused ? "paused" : "playing", speed);
    return text;
  }
};

// Which messages a picture shows, e.g. "frame 50, haptic step 1500, device sample 1502", and
// the rigid object the tool holds or touches, e.g. ", cube grabbed".
std::string Describe(const ViewState& state, const config::Scene& scene) {
  char text[160];
  std::snprintf(text, sizeof(text), "frame %lld, haptic step %lld, device sample %lld",
                state.has_frame ? static_cast<long long>(state.frame.sequence) : -1LL,
                state.has_haptic ? static_cast<long long>(state.haptic.step) : -1LL,
                state.has_device ? static_cast<long long>(state.device.sequence) : -1LL);
  std::string description = text;
  const auto name_of = [&](int i) {
    return i >= 0 && i < static_cast<int>(scene.rigid_objects.size())
               ? scene.rigid_objects[i].object.name
               : std::string("object ") + std::to_string(i);
  };
  if (state.has_frame && state.frame.grabbed_object >= 0)
    description += ", " + name_of(state.frame.grabbed_object) + " grabbed";
  else if (state.has_frame && state.frame.selected_object >= 0)
    description += ", " + name_of(state.frame.selected_object) + " selected";
  return description;
}

// The task's score over the whole logged run, and when each target was reached (never: +inf).
nlohmann::json ScoreLoggedRun(const config::Scene& scene, const RunTimeline& timeline,
                              double haptic_dt_s, std::vector<double>* reached_at_s) {
  PalpationScorer scorer(*scene.task, scene.tool->model.shape,
                         scene.tool->model.mass_kg * scene.gravity_m_s2, haptic_dt_s);
  for (const hapsim_lcm::haptic_state_t& state : timeline.HapticStatesAfter(-1)) scorer.Add(state);
  const nlohmann::json score = scorer.ToJson();
  for (const nlohmann::json& target : score["targets"])
    reached_at_s->push_back(target.value("reached_at_s", std::numeric_limits<double>::infinity()));
  return score;
}

void ViewLog(const ViewOptions& options) {
  const LoggedRun run = ReadLoggedRun(options.log_path, options.run_id);
  const config::Scene scene = options.scene_path.empty()
                                  ? LoadLoggedScene(run.info, options.log_path)
                                  : config::LoadScene(options.scene_path);
  const RunTimeline& timeline = *run.timeline;
  // The task's targets turn green at the time the run reached them.
  std::vector<double> reached_at_s;
  if (scene.task && scene.tool) {
    const nlohmann::json score =
        ScoreLoggedRun(scene, timeline, 1.0 / run.info.haptic_rate_hz, &reached_at_s);
    if (!options.score_path.empty()) {
      WriteFileAtomically(options.score_path,
                          [&](std::ostream& out) { out << score.dump(2) << '\n'; });
      std::printf("hapsim view: %d of %zu targets reached in %s -> %s\n",
                  score["targets_reached"].get<int>(), scene.task->targets.size(),
                  options.log_path.c_str(), options.score_path.c_str());
      return;
    }
  } else if (!options.score_path.empty()) {
    throw InputError(options.log_path, 0, "task", "the logged scene has no task to score");
  }
  const auto state_at = [&](double t_s) {
    ViewState state = timeline.StateAt(t_s);
    for (const double at_s : reached_at_s) state.targets_reached.push_back(at_s <= t_s + 1e-9);
    return state;
  };
  const bool interactive = options.screenshot_path.empty() && options.video_path.empty();
  ViewWindow window("hapsim view: " + scene.name, scene, ParseWindowSize(options.size, "--size"),
                    options.painter, interactive);
  if (options.displacement_from_s >= 0.0) {
    const ViewState reference = timeline.StateAt(options.displacement_from_s);
    if (reference.has_frame) window.SetDisplacementReference(reference.frame);
  }
  Player player;
  player.first_s = timeline.first_frame_s();
  player.last_s = timeline.last_frame_s();
  player.frame_s = timeline.visual_dt_s();
  player.speed = options.speed;
  if (!options.screenshot_path.empty()) {
    const double t_s = options.at_s >= 0.0 ? options.at_s : player.last_s;
    const ViewState state = state_at(t_s);
    window.Show(state);
    window.SaveScreenshot(options.screenshot_path);
    std::printf("hapsim view: %s at %.3f s (%s) -> %s\n", options.log_path.c_str(), t_s,
                Describe(state, scene).c_str(), options.screenshot_path.c_str());
    return;
  }
  if (!options.video_path.empty()) {
    const long num_frames =
        std::lround((player.last_s - player.first_s) * options.fps / options.speed) + 1;
    for (long k = 0; k < num_frames && !g_stop_requested.load(); ++k) {
      window.Show(state_at(player.first_s + k * options.speed / options.fps));
      window.AddVideoFrame(options.video_path, options.fps);
    }
    window.FinishVideo();
    std::printf("hapsim view: %ld frames of %s at %g fps -> %s\n", num_frames,
                options.log_path.c_str(), options.fps, options.video_path.c_str());
    return;
  }
  player.t_s = player.first_s;
  const std::int64_t period_ns = std::llround(1e9 / options.fps);
  std::int64_t deadline_ns = MonotonicNs();
  while (!window.closed() && !g_stop_requested.load()) {
    bool quit = false;
    for (const WindowEvent& event : window.Poll()) {
      if (event.type != WindowEvent::Type::kKey) continue;
      quit = quit || event.key == "q" || event.key == "Escape";
      player.OnKey(event.key);
    }
    if (quit) break;
    ViewState state = state_at(player.t_s);
    state.status = player.Status();
    window.Show(state);
    deadline_ns += period_ns;
    SleepUntil(deadline_ns);
    if (!player.paused) {
      player.t_s += player.speed / options.fps;
      if (player.t_s >= player.last_s) player.Seek(0.0);  // stop at the end
    }
  }
}

void ViewLive(const ViewOptions& options) {
  std::int64_t run_id = 0;
  if (!options.run_id.empty() && !messages::ParseRunId(options.run_id, &run_id))
    throw InputError("", 0, "--run-id",
                     "not 1-16 hex digits (and not 0): '" + options.run_id + "'");
  lcm::LCM lcm(options.lcm_url);
  if (!lcm.good()) throw std::runtime_error("LCM: cannot open " + options.lcm_url);
  LiveRun live(&lcm, run_id, "hapsim view");
  ReceiveThread receiver(&lcm);
  // Said once subscribed: a run started after this line is seen from its first message (one
  // started before it shows only from the RUN_INFO it repeats about every second).
  std::printf("hapsim view: listening on %s\n", options.lcm_url.c_str());
  std::fflush(stdout);
  const std::optional<hapsim_lcm::run_info_t> info = live.WaitForRunInfo(options.wait_s);
  if (!info)
    throw std::runtime_error("no run heard on " + options.lcm_url + " within " +
                             std::to_string(options.wait_s) + " s (is `hapsim run` running?)");
  const config::Scene scene = options.scene_path.empty() ? LoadLoggedScene(*info, "RUN_INFO")
                                                         : config::LoadScene(options.scene_path);
  std::printf("hapsim view: run %s (%s)\n", messages::FormatRunId(info->run_id).c_str(),
              scene.name.c_str());
  std::fflush(stdout);
  RunTimeline& timeline = *live.timeline();
  ViewWindow window("hapsim view: " + scene.name, scene, ParseWindowSize(options.size, "--size"),
                    options.painter, options.screenshot_path.empty());
  const std::int64_t period_ns = std::llround(1e9 / options.fps);
  // Frames have come, then neither of the run's processes is heard for this long: the run has
  // ended. A live haptic process is heard every millisecond, but a viewer starved of the CPU (a
  // sanitized build on a loaded host) has gone over a second without taking a message in; 5 s keeps
  // it from taking a slow run for an ended one, at the price of 5 s after a run's real end.
  const double end_quiet_s = 5.0;
  const auto ended = [&] {
    return timeline.has_frames() && live.SecondsSinceLastMessage() > end_quiet_s;
  };
  if (!options.screenshot_path.empty()) {
    // The picture at `at` by the log's rule: wait until the frame after it has come, so that
    // the haptic states up to it have too (the haptic loop runs ahead of the frames).
    const double at_s = std::max(options.at_s, 0.0);
    const std::int64_t give_up_ns = MonotonicNs() + std::llround(1e9 * options.wait_s);
    while (!g_stop_requested.load() && !ended() && timeline.last_frame_s() <= at_s + 1e-6) {
      if (!timeline.has_frames() && MonotonicNs() > give_up_ns)
        throw std::runtime_error("the run sent no SIM_FRAME within " +
                                 std::to_string(options.wait_s) + " s of its RUN_INFO");
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    const ViewState state = timeline.StateAt(at_s);
    if (timeline.last_frame_s() <= at_s + 1e-6 && !g_stop_requested.load())
      std::fprintf(stderr,
                   "hapsim view: warning: no frame after %.3f s came (the run went quiet at frame "
                   "time %.3f s): the picture shows the newest state heard\n",
                   at_s, timeline.last_frame_s());
    window.Show(state);
    window.SaveScreenshot(options.screenshot_path);
    std::printf("hapsim view: live at %.3f s (%s) -> %s\n", at_s, Describe(state, scene).c_str(),
                options.screenshot_path.c_str());
    return;
  }
  const std::int64_t start_ns = MonotonicNs();
  std::int64_t deadline_ns = start_ns;
  while (!window.closed() && !g_stop_requested.load()) {
    bool quit = false;
    for (const WindowEvent& event : window.Poll())
      quit = quit ||
             (event.type == WindowEvent::Type::kKey && (event.key == "q" || event.key == "Escape"));
    if (quit) break;
    window.Show(timeline.StateAt(timeline.last_frame_s()));
    timeline.Forget(5.0);
    deadline_ns += period_ns;
    SleepUntil(deadline_ns);
    if (!options.video_path.empty()) {
      window.AddVideoFrame(options.video_path, options.fps);
      const bool long_enough =
          options.duration_s > 0.0 &&
          1e-9 * static_cast<double>(MonotonicNs() - start_ns) >= options.duration_s;
      if (ended() || long_enough) break;
    }
  }
  window.FinishVideo();
}

void RunView(const ViewOptions& options) {
  if (!options.screenshot_path.empty() && !options.video_path.empty())
    throw InputError("", 0, "--video", "give --screenshot or --video, not both");
  InstallStopHandlers();
  if (options.log_path.empty()) {
    ViewLive(options);
  } else {
    ViewLog(options);
  }
}

}  // namespace

void AddViewCommand(CLI::App* app) {
  auto options = std::make_shared<ViewOptions>();
  CLI::App* view = app->add_subcommand(
      "view",
      "3D viewer of a run: the tissue coloured by displacement, rigid objects, the tool and the\n"
      "device's ghost, contacts, the force arrow and a gauge of the device force and the haptic\n"
      "loop. With LOG it plays the logged run (space pause, . , frame, ] [ second, up down\n"
      "speed, Home start, q quit); without, it shows the run live over LCM. Needs an X display\n"
      "(Xvfb for headless --screenshot and --video).");
  view->add_option("log", options->log_path, "LCM log of a run (hapsim run --log); none: live");
  view->add_option("--lcm-url", options->lcm_url, "LCM URL of the live run")->capture_default_str();
  view->add_option("--run-id", options->run_id,
                   "The run (hex): required for a log of several runs; live default: the first "
                   "heard");
  view->add_option("--scene", options->scene_path, "Draw with this scene, not the run's own");
  view->add_option("--screenshot", options->screenshot_path,
                   "Write the picture at --at to FILE.png and exit");
  view->add_option("--at", options->at_s, "Time of the screenshot, s (default: the last frame)")
      ->check(CLI::NonNegativeNumber);
  view->add_option(
      "--video", options->video_path,
      "Write the run as FILE.avi (MJPG) and exit (live: until the run ends, i.e. 5 s after "
      "its processes go quiet, or --duration)");
  view->add_option("--fps", options->fps, "Frames per second of the window and the video")
      ->check(CLI::Range(1.0, 240.0))
      ->capture_default_str();
  view->add_option("--speed", options->speed, "Playback speed of a log")
      ->check(CLI::Range(1.0 / 16.0, 16.0))
      ->capture_default_str();
  view->add_option("--duration", options->duration_s, "Live --video: seconds to record")
      ->check(CLI::NonNegativeNumber);
  view->add_option("--size", options->size, "Window size")->capture_default_str();
  view->add_option("--wait", options->wait_s, "Live: seconds to wait for the run")
      ->check(CLI::Range(0.001, 86400.0))
      ->capture_default_str();
  view->add_option("--displacement-scale", options->painter.displacement_scale_m,
                   "Displacement drawn in the deepest red, m (default: 5 mm, or a quarter of the "
                   "body's smallest size if less)")
      ->check(CLI::PositiveNumber);
  view->add_option("--score", options->score_path,
                   "Score the logged run's task (as `hapsim train` does), write FILE.json, exit");
  view->add_option("--displacement-from", options->displacement_from_s,
                   "Colour displacements from the body's shape at this time, s (a log; default: "
                   "from the rest shape)")
      ->check(CLI::NonNegativeNumber);
  view->callback([options] { RunView(*options); });
}

}  // namespace hapsim::apps
