#include "view/trainer.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "contact/rigid_objects.h"
#include "core/atomic_file.h"
#include "core/realtime.h"
#include "messages/message_gate.h"

namespace hapsim::view {
namespace {

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

}  // namespace

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
    // A retraction's target may lie above where the tool starts (the tissue pulled up).
    const double down_mm = 1e3 * (start_W_m.z() - tip_m - target.position_m.z());
    std::printf("  target %s: pointer at (%.0f, %.0f), touches %.0f mm %s\n", target.name.c_str(),
                pixel.x, pixel.y, std::abs(down_mm), down_mm >= 0.0 ? "down" : "up");
  }
  std::printf(
      "  mouse: move in the plane; wheel or Up/Down: depth; b: button; s: screenshot; "
      "q: end\n");
  std::fflush(stdout);
}

// Feeds the scorer the haptic states and frames that came since its last, saying which targets
// that reached and when tissue slipped from the jaws.
void ScoreNewStates(const RunTimeline& timeline, const config::TaskScene& task,
                    PalpationScorer* scorer) {
  const std::vector<bool> before = scorer->reached();
  for (const hapsim_lcm::haptic_state_t& haptic : timeline.HapticStatesAfter(scorer->last_step()))
    scorer->Add(haptic);
  for (const RunTimeline::GraspCount& frame : timeline.GraspCountsAfter(scorer->last_frame())) {
    scorer->AddFrame(frame.sequence, frame.num_grasped, frame.num_slipped);
    if (frame.num_slipped > 0)
      std::printf("hapsim train: t %.2f s: %d points slipped from the jaws (tissue torn)\n",
                  scorer->elapsed_s(), frame.num_slipped);
  }
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
  const std::string torn =
      score.contains("grip_slipped_points")
          ? "; " + std::to_string(scorer.points_slipped()) + " points slipped from the jaws"
          : "";
  std::printf(
      "hapsim train: %d of %zu targets in %.2f s; peak force %.2f N, %.2f s over the %.1f N "
      "limit, tool path %.3f m%s\n  wrote %s and %s (the run %s)\n",
      score["targets_reached"].get<int>(), scene.task->targets.size(), scorer.elapsed_s(),
      score["peak_force_N"].get<double>(), score["time_over_force_limit_s"].get<double>(),
      scene.task->force_limit_N, score["tool_path_length_m"].get<double>(), torn.c_str(),
      score_path.c_str(), log_path.c_str(), run_end.c_str());
}

void RunTrainingLoop(LiveRun* live, ViewWindow* window, MouseDevice* mouse,
                     const config::TaskScene& task, const Eigen::Vector3d& start_W_m,
                     const TrainOptions& options, const std::string& out_dir,
                     PalpationScorer* scorer, const std::function<bool()>& run_ended) {
  TraineeInput input;
  input.pointer_W_m = start_W_m;
  int screenshots = 0;
  bool reference_set = false;
  double done_at_s = -1.0;
  // 15 pictures a second: with software OpenGL (Xvfb, no GPU) a 800 x 600 picture takes ~40 ms
  // of a core, and the two simulation processes need the rest of two cores.
  const std::int64_t period_ns = std::llround(1e9 / 15.0);
  std::int64_t deadline_ns = MonotonicNs();
  while (!input.quit && !window->closed() && !g_stop_requested.load()) {
    TakeInput(window->Poll(), *window, start_W_m.z(), options.depth_step_m, &input);
    if (input.screenshot) {
      const std::string path = out_dir + "/screenshot_" + std::to_string(++screenshots) + ".png";
      window->SaveScreenshot(path);
      std::printf("hapsim train: t %.2f s: screenshot %s\n", scorer->elapsed_s(), path.c_str());
      std::fflush(stdout);
    }
    if (mouse)
      mouse->SetTarget(input.pointer_W_m - input.depth_m * Eigen::Vector3d::UnitZ(), input.buttons);
    RunTimeline* timeline = live->timeline();
    ViewState state;
    if (timeline != nullptr) {
      ScoreNewStates(*timeline, task, scorer);
      state = timeline->StateAt(timeline->last_frame_s());
      if (!reference_set && state.has_frame && state.frame.t_s >= options.settle_s) {
        window->SetDisplacementReference(state.frame);
        reference_set = true;
        std::printf("hapsim train: t %.2f s: displacements coloured from the frame at %.2f s\n",
                    scorer->elapsed_s(), state.frame.t_s);
        std::fflush(stdout);
      }
      timeline->Forget(5.0);
    }
    state.targets_reached = scorer->reached();
    state.status = scorer->StatusLine() + (input.buttons ? "   [button]" : "");
    window->Show(state);
    if (scorer->completed() && done_at_s < 0.0) done_at_s = scorer->elapsed_s();
    // Done: every target reached (a second more to see it), or the run ended (the time limit).
    if (done_at_s >= 0.0 && scorer->elapsed_s() > done_at_s + 1.0) input.quit = true;
    if (run_ended()) break;
    deadline_ns += period_ns;
    SleepUntil(deadline_ns);
  }
}

}  // namespace hapsim::view
