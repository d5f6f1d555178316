// `hapsim view [LOG]`: the 3D viewer (OpenCV viz, i.e. VTK). With a log it plays the logged run
// (keys: space pause, . and , a frame forward and back, ] and [ a second, up and down the speed,
// Home the start, q quit); without one it shows the run live over LCM from SIM_FRAME, HAPTIC_STATE
// and DEVICE_STATE, the scene taken from the run's RUN_INFO. Headless (under Xvfb):
// --screenshot FILE.png [--at S] and --video FILE.avi. Here: the options, the log read or the
// live run waited for, and the run's scene loaded; view/viewer.h shows it.

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "apps/commands.h"
#include "apps/run_info.h"
#include "config/scene.h"
#include "core/error.h"
#include "core/realtime.h"
#include "messages/channels.h"
#include "messages/receive_thread.h"
#include "view/live_run.h"
#include "view/run_timeline.h"
#include "view/viewer.h"

namespace hapsim::apps {
namespace {

using view::ViewOptions;

void ViewLog(const ViewOptions& options) {
  const view::LoggedRun run = view::ReadLoggedRun(options.log_path, options.run_id);
  const config::Scene scene = options.scene_path.empty()
                                  ? LoadLoggedScene(run.info, options.log_path)
                                  : config::LoadScene(options.scene_path);
  view::PlayLoggedRun(run, scene, options);
}

void ViewLive(const ViewOptions& options) {
  std::int64_t run_id = 0;
  if (!options.run_id.empty() && !messages::ParseRunId(options.run_id, &run_id))
    throw InputError("", 0, "--run-id",
                     "not 1-16 hex digits (and not 0): '" + options.run_id + "'");
  lcm::LCM lcm(options.lcm_url);
  if (!lcm.good()) throw std::runtime_error("LCM: cannot open " + options.lcm_url);
  view::LiveRun live(&lcm, run_id, "hapsim view");
  messages::ReceiveThread receiver(&lcm);
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
  view::ShowLiveRun(&live, scene, options);
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
  view->add_flag("--side-view", options->painter.side_view,
                 "Add a second view from the side, level with the scene (an inset, top right): "
                 "how far the tool is from the tissue, seen as height");
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
