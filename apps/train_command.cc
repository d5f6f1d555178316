// `hapsim train SCENE`: the surgical training prototype. Starts the two processes as `hapsim run`
// does (the device external), opens the viewer, and lets the trainee drive the tool: the mouse
// moves it in a horizontal plane under the pointer, the wheel or Up / Down (Page_Up / Page_Down)
// move it down and up, b toggles the device button; or a real device through the external-driver
// protocol (--device external). The scene's task (targets, force band, limit, time) is scored
// live: reached targets turn green, a warning shows above the force limit. At the end the score
// is shown and written as JSON; the run's log replays with `hapsim replay` and plays with
// `hapsim view`. Here: the options, the run started and stopped, the score written; the session
// itself (window, mouse device, live score) is view/trainer.h's.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Core>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "apps/child_process.h"
#include "apps/commands.h"
#include "config/scene.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/realtime.h"
#include "messages/channels.h"
#include "messages/message_gate.h"
#include "messages/receive_thread.h"
#include "view/live_run.h"
#include "view/mouse_device.h"
#include "view/palpation_score.h"
#include "view/trainer.h"
#include "view/view_window.h"

namespace hapsim::apps {
namespace {

using view::TrainOptions;

// Stops the run (SIGINT: `hapsim run` ends its haptic process and completes its log) and waits;
// after 5 s, kills it (SIGKILL: its log may then be incomplete). Returns its exit status.
int StopRun(pid_t child, std::string* how) {
  int code = 0;
  *how = CheckChild(child, &code);
  if (!how->empty()) return code;
  kill(child, SIGINT);
  for (int i = 0; i < 500; ++i) {
    *how = CheckChild(child, &code);
    if (!how->empty()) return code;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  kill(child, SIGKILL);
  waitpid(child, nullptr, 0);
  *how = "did not stop within 5 s of SIGINT and was killed (its log may be incomplete)";
  return 128 + SIGKILL;
}

void RunTrain(TrainOptions options) {
  const config::Scene scene = config::LoadScene(options.scene_path);
  if (!scene.tool) throw InputError(scene.file, 0, "tool", "`hapsim train` needs a tool");
  if (!scene.task)
    throw InputError(scene.file, 0, "task", "`hapsim train` needs the scene's task (targets)");
  if (options.device != "mouse" && options.device != "external")
    throw InputError("", 0, "--device", "must be mouse or external, got '" + options.device + "'");
  const config::TaskScene& task = *scene.task;
  const cv::Size size = view::ParseWindowSize(options.size, "--size");
  const std::string out_dir =
      options.out_dir.empty() ? "out/" + scene.name + "_train" : options.out_dir;
  CreateOutputDirectory(out_dir);
  const std::string log_path = out_dir + "/run.lcm", score_path = out_dir + "/score.json",
                    haptic_summary_path = out_dir + "/haptic_summary.json";
  const std::int64_t run_id = messages::MakeRunId();
  const double haptic_dt_s = 1.0 / scene.haptic.rate_hz;
  InstallStopHandlers();
  // Mesa's software renderer (Xvfb, machines without a GPU) takes a thread per core by default:
  // one is enough for the window, and leaves the cores to the two simulation processes (with
  // two, the visual process fell 1.2 s behind the haptic clock in 8 s).
  setenv("LP_NUM_THREADS", "1", /*overwrite=*/0);

  lcm::LCM lcm(options.lcm_url);
  if (!lcm.good()) throw std::runtime_error("LCM: cannot open " + options.lcm_url);
  view::LiveRun live(&lcm, run_id, "hapsim train");
  messages::ReceiveThread receiver(&lcm);
  view::PainterOptions painter;
  painter.side_view = options.side_view;
  view::ViewWindow window("hapsim train: " + scene.name, scene, size, painter, true);
  // The handle starts where the scene's device starts, so that the tool starts at rest.
  const Eigen::Vector3d start_W_m =
      scene.trajectory.empty() ? scene.tool->initial_state.x_W_m : scene.trajectory[0].x_W_m;
  std::unique_ptr<view::MouseDevice> mouse;
  if (options.device == "mouse")
    mouse = std::make_unique<view::MouseDevice>(&lcm, run_id, start_W_m, haptic_dt_s);
  const pid_t child = SpawnSelf(
      {"hapsim", "run", options.scene_path, "--device", "external", "--lcm-url", options.lcm_url,
       "--run-id", messages::FormatRunId(run_id), "--log", log_path, "--haptic-summary",
       haptic_summary_path, "--duration", std::to_string(task.time_limit_s)},
      "the visual process");
  std::printf(
      "hapsim train: %s, run %s; %zu targets, force band %.2f-%.2f N, hold %.2f s, limit "
      "%.2f N, %.0f s\n",
      scene.name.c_str(), messages::FormatRunId(run_id).c_str(), task.targets.size(),
      task.force_band_min_N, task.force_band_max_N, task.hold_s, task.force_limit_N,
      task.time_limit_s);
  view::PrintTargetHints(scene, start_W_m, window);
  view::PalpationScorer scorer(task, scene.tool->model.shape,
                               scene.tool->model.mass_kg * scene.gravity_m_s2, haptic_dt_s,
                               scene.tool->grasp.has_value());
  int child_code = 0;
  std::string child_end;
  // Whatever ends the session (the task, the time limit, q, an error such as a screenshot that
  // cannot be written), the run is stopped and the score written.
  std::exception_ptr failure;
  try {
    view::RunTrainingLoop(&live, &window, mouse.get(), task, start_W_m, options, out_dir, &scorer,
                          [&] {
                            child_end = CheckChild(child, &child_code);
                            return !child_end.empty();
                          });
  } catch (...) {
    failure = std::current_exception();
  }
  if (child_end.empty()) {
    child_code = StopRun(child, &child_end);
    if (child_code == 0 || child_code == 130) child_end = "stopped";
  }
  if (view::RunTimeline* timeline = live.timeline()) view::ScoreNewStates(*timeline, task, &scorer);
  view::WriteScore(scorer, scene, run_id, log_path, score_path, child_end);
  if (failure) std::rethrow_exception(failure);
  // 130: the run was interrupted (our own SIGINT or the trainee's q): its log is complete.
  if (child_code != 0 && child_code != 130)
    throw std::runtime_error("the visual process " + child_end);
}

}  // namespace

void AddTrainCommand(CLI::App* app) {
  auto options = std::make_shared<TrainOptions>();
  CLI::App* train = app->add_subcommand(
      "train",
      "The surgical training prototype: runs the scene as `hapsim run` does and opens the\n"
      "viewer; the trainee drives the tool with the mouse (a horizontal plane under the\n"
      "pointer), the wheel or Up/Down (depth) and b (the device button), or with a real device\n"
      "(--device external, docs/DEVICE.md). The scene's task is scored live; the score is\n"
      "written as JSON beside the run's LCM log. Needs an X display.");
  train->add_option("scene", options->scene_path, "Scene file (YAML) with a tool and a task")
      ->required();
  train->add_option("--device", options->device, "mouse, or external (a driver over LCM)")
      ->capture_default_str();
  train->add_option("--lcm-url", options->lcm_url, "LCM URL of the run")->capture_default_str();
  train->add_option("--out", options->out_dir,
                    "Folder for run.lcm, score.json, haptic_summary.json and screenshots\n"
                    "(default out/<scene>_train)");
  train->add_option("--size", options->size, "Window size")->capture_default_str();
  train->add_flag("--side-view", options->side_view,
                  "Add a second view from the side (an inset, top right); the mouse still moves "
                  "the tool in the main view's plane");
  train
      ->add_option("--settle", options->settle_s,
                   "Colour displacements from the shape at this time, s (after settling)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  train->callback([options] { RunTrain(*options); });
}

}  // namespace hapsim::apps
