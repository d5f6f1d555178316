// `hapsim train SCENE`: the surgical training prototype. Starts the two processes as `hapsim run`
// does (the device external), opens the viewer, and lets the trainee drive the tool: the mouse
// moves it in a horizontal plane under the pointer, the wheel or Up / Down (Page_Up / Page_Down)
// move it down and up, b toggles the device button; or a real device through the external-driver
// protocol (--device external). The scene's task (targets, force band, limit, time) is scored
// live: reached targets turn green, a warning shows above the force limit. At the end the score
// is shown and written as JSON; the run's log replays with `hapsim replay` and plays with
// `hapsim view`.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "apps/child_process.h"
#include "apps/commands.h"
#include "apps/live_run.h"
#include "apps/palpation_score.h"
#include "apps/realtime.h"
#include "apps/receive_thread.h"
#include "apps/view_window.h"
#include "config/scene.h"
#include "contact/rigid_objects.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "messages/channels.h"
#include "messages/message_gate.h"

namespace hapsim::apps {
namespace {

struct TrainOptions {
  std::string scene_path;
  std::string lcm_url = messages::kDefaultLcmUrl;
  std::string device = "mouse";  // mouse | external
  std::string out_dir;           // default out/<scene>_train
  std::string size = "800x600";
  double settle_s = 1.0;        // displacements are coloured from the shape at this time
  double depth_step_m = 0.002;  // per wheel notch or key press
};

// The handle driven by the mouse: the window sets a target, a 1 kHz thread publishes DEVICE_STATE
// (the external-driver protocol, docs/DEVICE.md) following it through a first-order filter of
// 20 ms and at most 0.3 m/s, so that the device moves as a hand does: smoothly, not in the
// window's 15 Hz steps, and not 6 cm in a frame when the pointer jumps (a 6.5 N coupling spike
// through the coupling's damping, seen before the limit).
class MouseDevice {
 public:
  MouseDevice(lcm::LCM* lcm, std::int64_t run_id, const Eigen::Vector3d& start_W_m, double dt_s)
      : lcm_(lcm), run_id_(run_id), dt_s_(dt_s), target_W_m_(start_W_m), x_W_m_(start_W_m) {
    thread_ = std::thread([this] { Loop(); });
  }
  ~MouseDevice() {
    running_.store(false);
    thread_.join();
  }
  void SetTarget(const Eigen::Vector3d& x_W_m, int buttons) {
    std::lock_guard<std::mutex> lock(mutex_);
    target_W_m_ = x_W_m;
    buttons_ = buttons;
  }

 private:
  void Loop() {
    // As time-critical as the haptic loop: a DEVICE_STATE later than the haptic process's
    // device_stale_s (5 ms) zeroes the force (seen while the window rendered, before this).
    const std::string rt_failure = RequestRealtime(70);
    if (!rt_failure.empty())
      std::fprintf(stderr, "hapsim train: warning: the device thread runs unprioritised (%s)\n",
                   rt_failure.c_str());
    constexpr double kTimeConstant_s = 0.02;
    const double alpha = dt_s_ / (kTimeConstant_s + dt_s_);
    const std::int64_t period_ns = std::llround(1e9 * dt_s_);
    std::int64_t deadline_ns = MonotonicNs();
    long sequence = 0;
    while (running_.load()) {
      Eigen::Vector3d target;
      int buttons;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        target = target_W_m_;
        buttons = buttons_;
      }
      DeviceState device;
      Eigen::Vector3d step_m = alpha * (target - x_W_m_);
      if (step_m.norm() > kMaxSpeed_m_s * dt_s_) step_m *= kMaxSpeed_m_s * dt_s_ / step_m.norm();
      device.v_W_m_s = step_m / dt_s_;
      x_W_m_ += step_m;
      device.x_W_m = x_W_m_;
      device.buttons = buttons;
      hapsim_lcm::device_state_t msg = messages::ToMessage(device, WallMicros(), sequence++);
      msg.run_id = run_id_;
      lcm_->publish(messages::kDeviceStateChannel, &msg);
      deadline_ns += period_ns;
      // Held off the CPU for more than a period: start again from now, rather than publish
      // the missed samples back to back.
      if (MonotonicNs() > deadline_ns + period_ns) deadline_ns = MonotonicNs();
      SleepUntil(deadline_ns);
    }
  }

  static constexpr double kMaxSpeed_m_s = 0.3;
  lcm::LCM* lcm_;
  std::int64_t run_id_;
  double dt_s_;
  std::mutex mutex_;
  Eigen::Vector3d target_W_m_;
  int buttons_ = 0;
  Eigen::Vector3d x_W_m_;  // the loop's filtered position
  std::atomic<bool> running_{true};
  std::thread thread_;
};

// Where the pointer's ray meets the horizontal plane z = plane_z_m, world; nullopt when the ray
// runs (nearly) parallel to it or meets it behind the camera. The camera follows OpenCV's
// convention (x right, y down the picture, z forward).
std::optional<Eigen::Vector3d> PointUnderPointer(cv::viz::Viz3d& renderer, int u, int v,
                                                 double plane_z_m) {
  const cv::viz::Camera camera = renderer.getCamera();
  const cv::Affine3d pose = renderer.getViewerPose();
  const cv::Vec2d focal = camera.getFocalLength(), centre = camera.getPrincipalPoint();
  const cv::Vec3d ray_C((u - centre[0]) / focal[0], (v - centre[1]) / focal[1], 1.0);
  const cv::Vec3d ray_W = pose.rotation() * ray_C, origin_W = pose.translation();
  if (std::abs(ray_W[2]) < 1e-6) return std::nullopt;
  const double t = (plane_z_m - origin_W[2]) / ray_W[2];
  if (t <= 0.0) return std::nullopt;
  const cv::Vec3d p = origin_W + t * ray_W;
  return Eigen::Vector3d(p[0], p[1], p[2]);
}

// The pixel of the world point p_W (for the trainee's hints and scripted sessions).
cv::Point2d PixelOf(cv::viz::Viz3d& renderer, const Eigen::Vector3d& p_W) {
  const cv::viz::Camera camera = renderer.getCamera();
  const cv::Vec3d p_C = renderer.getViewerPose().inv() * cv::Vec3d(p_W.x(), p_W.y(), p_W.z());
  const cv::Vec2d focal = camera.getFocalLength(), centre = camera.getPrincipalPoint();
  return {focal[0] * p_C[0] / p_C[2] + centre[0], focal[1] * p_C[1] / p_C[2] + centre[1]};
}

// What the trainee asks for through the window.
struct TraineeInput {
  Eigen::Vector3d pointer_W_m = Eigen::Vector3d::Zero();  // under the pointer, in the plane
  double depth_m = 0.0;                                   // below the plane, ≥ 0
  int buttons = 0;                                        // bit 0: the device button
  bool screenshot = false;                                // this frame: s was pressed
  bool quit = false;
};

// The mouse moves the pointer's point; the wheel or Up/Down (Page_Up/Page_Down) change the depth
// by depth_step_m; b toggles the button; s asks for a screenshot; q or Escape ends.
void TakeInput(const std::vector<WindowEvent>& events, ViewWindow& window, double plane_z_m,
               double depth_step_m, TraineeInput* input) {
  using Type = WindowEvent::Type;
  input->screenshot = false;
  for (const WindowEvent& event : events) {
    const bool key = event.type == Type::kKey;
    if (event.type == Type::kMouseMove) {
      if (const auto point = PointUnderPointer(window.renderer(), event.x, event.y, plane_z_m))
        input->pointer_W_m = *point;
    }
    if (event.type == Type::kWheelUp || (key && (event.key == "Up" || event.key == "Page_Up")))
      input->depth_m = std::max(0.0, input->depth_m - depth_step_m);
    if (event.type == Type::kWheelDown ||
        (key && (event.key == "Down" || event.key == "Page_Down")))
      input->depth_m += depth_step_m;
    if (key && event.key == "b") input->buttons ^= 1;
    if (key && event.key == "s") input->screenshot = true;
    if (key && (event.key == "q" || event.key == "Escape")) input->quit = true;
  }
}

// Where each target is on the screen, and how far the tool must go down to touch it (for the
// trainee, and for scripted sessions); then the controls.
void PrintTargetHints(const config::Scene& scene, const Eigen::Vector3d& start_W_m,
                      ViewWindow& window) {
  // How far below its centre the upright tool reaches: the bottom of its bounding box.
  contact::RigidObject upright_tool;
  upright_tool.shape = scene.tool->model.shape;
  const double tip_m = -contact::CalcWorldBox(upright_tool).min().z();
  for (const config::PalpationTarget& target : scene.task->targets) {
    const Eigen::Vector3d above(target.position_m.x(), target.position_m.y(), start_W_m.z());
    const cv::Point2d pixel = PixelOf(window.renderer(), above);
    std::printf("  target %s: pointer at (%.0f, %.0f), touches %.0f mm down\n", target.name.c_str(),
                pixel.x, pixel.y, 1e3 * (start_W_m.z() - tip_m - target.position_m.z()));
  }
  std::printf(
      "  mouse: move in the plane; wheel or Up/Down: depth; b: button; s: screenshot; "
      "q: end\n");
  std::fflush(stdout);
}

// Feeds the scorer the haptic states that came since its last, saying which targets that reached.
void ScoreNewStates(const RunTimeline& timeline, const config::TaskScene& task,
                    PalpationScorer* scorer) {
  const std::vector<bool> before = scorer->reached();
  for (const hapsim_lcm::haptic_state_t& haptic : timeline.HapticStatesAfter(scorer->last_step()))
    scorer->Add(haptic);
  const std::vector<bool> reached = scorer->reached();
  for (size_t i = 0; i < reached.size(); ++i) {
    if (reached[i] && !before[i])
      std::printf("hapsim train: t %.2f s: target %s reached\n", scorer->elapsed_s(),
                  task.targets[i].name.c_str());
  }
  std::fflush(stdout);
}

// score.json (atomically) and the score on the terminal.
void WriteScore(const PalpationScorer& scorer, const config::Scene& scene, std::int64_t run_id,
                const std::string& log_path, const std::string& score_path,
                const std::string& run_end) {
  nlohmann::json score = scorer.ToJson();
  score["scene"] = scene.name;
  score["run_id"] = messages::FormatRunId(run_id);
  score["log"] = log_path;
  WriteFileAtomically(score_path, [&](std::ostream& out) { out << score.dump(2) << '\n'; });
  std::printf(
      "hapsim train: %d of %zu targets in %.2f s; peak force %.2f N, %.2f s over the %.1f N "
      "limit, tool path %.3f m\n  wrote %s and %s (the run %s)\n",
      score["targets_reached"].get<int>(), scene.task->targets.size(), scorer.elapsed_s(),
      score["peak_force_N"].get<double>(), score["time_over_force_limit_s"].get<double>(),
      scene.task->force_limit_N, score["tool_path_length_m"].get<double>(), score_path.c_str(),
      log_path.c_str(), run_end.c_str());
}

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
  const cv::Size size = ParseWindowSize(options.size, "--size");
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
  LiveRun live(&lcm, run_id, "hapsim train");
  ReceiveThread receiver(&lcm);
  ViewWindow window("hapsim train: " + scene.name, scene, size, PainterOptions{}, true);
  // The handle starts where the scene's device starts, so that the tool starts at rest.
  const Eigen::Vector3d start_W_m =
      scene.trajectory.empty() ? scene.tool->initial_state.x_W_m : scene.trajectory[0].x_W_m;
  std::unique_ptr<MouseDevice> mouse;
  if (options.device == "mouse")
    mouse = std::make_unique<MouseDevice>(&lcm, run_id, start_W_m, haptic_dt_s);
  const pid_t child = SpawnSelf(
      {"hapsim", "run", options.scene_path, "--device", "external", "--lcm-url", options.lcm_url,
       "--run-id", messages::FormatRunId(run_id), "--log", log_path, "--haptic-summary",
       haptic_summary_path, "--duration", std::to_string(task.time_limit_s)},
      "the visual process");
  std::printf(
      "hapsim train: %s, run %s; %zu targets, force band %.1f-%.1f N, hold %.1f s, limit "
      "%.1f N, %.0f s\n",
      scene.name.c_str(), messages::FormatRunId(run_id).c_str(), task.targets.size(),
      task.force_band_min_N, task.force_band_max_N, task.hold_s, task.force_limit_N,
      task.time_limit_s);
  PrintTargetHints(scene, start_W_m, window);
  PalpationScorer scorer(task, scene.tool->model.shape,
                         scene.tool->model.mass_kg * scene.gravity_m_s2, haptic_dt_s);
  TraineeInput input;
  input.pointer_W_m = start_W_m;
  int screenshots = 0, child_code = 0;
  bool reference_set = false;
  double done_at_s = -1.0;
  std::string child_end;
  // 15 pictures a second: with software OpenGL (Xvfb, no GPU) a 800 x 600 picture takes ~40 ms
  // of a core, and the two simulation processes need the rest of two cores.
  const std::int64_t period_ns = std::llround(1e9 / 15.0);
  std::int64_t deadline_ns = MonotonicNs();
  // Whatever ends the session (the task, the time limit, q, an error such as a screenshot that
  // cannot be written), the run is stopped and the score written.
  std::exception_ptr failure;
  try {
    while (!input.quit && !window.closed() && !g_stop_requested.load()) {
      TakeInput(window.Poll(), window, start_W_m.z(), options.depth_step_m, &input);
      if (input.screenshot) {
        const std::string path = out_dir + "/screenshot_" + std::to_string(++screenshots) + ".png";
        window.SaveScreenshot(path);
        std::printf("hapsim train: t %.2f s: screenshot %s\n", scorer.elapsed_s(), path.c_str());
        std::fflush(stdout);
      }
      if (mouse)
        mouse->SetTarget(input.pointer_W_m - input.depth_m * Eigen::Vector3d::UnitZ(),
                         input.buttons);
      RunTimeline* timeline = live.timeline();
      ViewState state;
      if (timeline != nullptr) {
        ScoreNewStates(*timeline, task, &scorer);
        state = timeline->StateAt(timeline->last_frame_s());
        if (!reference_set && state.has_frame && state.frame.t_s >= options.settle_s) {
          window.SetDisplacementReference(state.frame);
          reference_set = true;
          std::printf("hapsim train: t %.2f s: displacements coloured from the frame at %.2f s\n",
                      scorer.elapsed_s(), state.frame.t_s);
          std::fflush(stdout);
        }
        timeline->Forget(5.0);
      }
      state.targets_reached = scorer.reached();
      state.status = scorer.StatusLine() + (input.buttons ? "   [button]" : "");
      window.Show(state);
      if (scorer.completed() && done_at_s < 0.0) done_at_s = scorer.elapsed_s();
      // Done: every target reached (a second more to see it), or the run ended (the time limit).
      if (done_at_s >= 0.0 && scorer.elapsed_s() > done_at_s + 1.0) input.quit = true;
      child_end = CheckChild(child, &child_code);
      if (!child_end.empty()) break;
      deadline_ns += period_ns;
      SleepUntil(deadline_ns);
    }
  } catch (...) {
    failure = std::current_exception();
  }
  if (child_end.empty()) {
    child_code = StopRun(child, &child_end);
    if (child_code == 0 || child_code == 130) child_end = "stopped";
  }
  if (RunTimeline* timeline = live.timeline()) ScoreNewStates(*timeline, task, &scorer);
  WriteScore(scorer, scene, run_id, log_path, score_path, child_end);
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
  train
      ->add_option("--settle", options->settle_s,
                   "Colour displacements from the shape at this time, s (after settling)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  train->callback([options] { RunTrain(*options); });
}

}  // namespace hapsim::apps
