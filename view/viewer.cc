#include "view/viewer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/realtime.h"
#include "view/palpation_score.h"
#include "view/view_window.h"

namespace hapsim::view {
namespace {

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

// Which messages a picture shows, e.g. "frame 50, haptic step 1500, device sample 1502", the
// rigid object the tool holds or touches, e.g. ", cube grabbed", and the tissue the jaws hold,
// e.g. ", 7 points grasped, 2 slipped from the jaws" (at the frame they slipped).
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
  if (state.has_frame && state.frame.num_grasped > 0)
    description += ", " + std::to_string(state.frame.num_grasped) + " points grasped";
  if (state.has_frame && state.frame.num_grasp_slipped > 0)
    description += ", " + std::to_string(state.frame.num_grasp_slipped) + " slipped from the jaws";
  return description;
}

// The task's score over the whole logged run, and when each target was reached (never: +inf).
nlohmann::json ScoreLoggedRun(const config::Scene& scene, const RunTimeline& timeline,
                              double haptic_dt_s, std::vector<double>* reached_at_s) {
  PalpationScorer scorer(*scene.task, scene.tool->model.shape,
                         scene.tool->model.mass_kg * scene.gravity_m_s2, haptic_dt_s,
                         scene.tool->grasp.has_value());
  for (const hapsim_lcm::haptic_state_t& state : timeline.HapticStatesAfter(-1)) scorer.Add(state);
  for (const RunTimeline::GraspCount& frame : timeline.GraspCountsAfter(-1))
    scorer.AddFrame(frame.sequence, frame.num_grasped, frame.num_slipped);
  const nlohmann::json score = scorer.ToJson();
  for (const nlohmann::json& target : score["targets"])
    reached_at_s->push_back(target.value("reached_at_s", std::numeric_limits<double>::infinity()));
  return score;
}

}  // namespace

void PlayLoggedRun(const LoggedRun& run, const config::Scene& scene, const ViewOptions& options) {
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

void ShowLiveRun(LiveRun* live, const config::Scene& scene, const ViewOptions& options) {
  RunTimeline& timeline = *live->timeline();
  ViewWindow window("hapsim view: " + scene.name, scene, ParseWindowSize(options.size, "--size"),
                    options.painter, options.screenshot_path.empty());
  const std::int64_t period_ns = std::llround(1e9 / options.fps);
  // Frames have come, then neither of the run's processes is heard for this long: the run has
  // ended. A live haptic process is heard every millisecond, but a viewer starved of the CPU (a
  // sanitized build on a loaded host) has gone over a second without taking a message in; 5 s keeps
  // it from taking a slow run for an ended one, at the price of 5 s after a run's real end.
  const double end_quiet_s = 5.0;
  const auto ended = [&] {
    return timeline.has_frames() && live->SecondsSinceLastMessage() > end_quiet_s;
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

}  // namespace hapsim::view
