#pragma once
// `hapsim train`'s session (apps/train_command.cc starts the run and stops it): the trainee's
// window, the mouse as the device, the task scored live from the run's haptic states, and the
// score at the end.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>

#include "config/scene.h"
#include "messages/channels.h"
#include "view/live_run.h"
#include "view/mouse_device.h"
#include "view/palpation_score.h"
#include "view/run_timeline.h"
#include "view/view_window.h"

namespace hapsim::view {

// `hapsim train`'s options (apps/train_command.cc binds them to the command line).
struct TrainOptions {
  std::string scene_path;
  std::string lcm_url = messages::kDefaultLcmUrl;
  std::string device = "mouse";  // mouse | external
  std::string out_dir;           // default out/<scene>_train
  std::string size = "800x600";
  double settle_s = 1.0;        // displacements are coloured from the shape at this time
  double depth_step_m = 0.002;  // per wheel notch or key press
  bool side_view = false;       // a second view from the side, as an inset (PainterOptions)
};

// Where each target is on the screen, and how far the tool must go down to touch it (for the
// trainee, and for scripted sessions); then the controls.
void PrintTargetHints(const config::Scene& scene, const Eigen::Vector3d& start_W_m,
                      ViewWindow& window);

// Feeds the scorer the haptic states that came since its last, saying which targets that reached.
void ScoreNewStates(const RunTimeline& timeline, const config::TaskScene& task,
                    PalpationScorer* scorer);

// score.json (atomically) and the score on the terminal.
void WriteScore(const PalpationScorer& scorer, const config::Scene& scene, std::int64_t run_id,
                const std::string& log_path, const std::string& score_path,
                const std::string& run_end);

// The session's window loop, 15 pictures a second, until the trainee ends it (q, Escape, the
// window closed, SIGINT or SIGTERM), a second after every target is reached, or `run_ended`
// (asked once a picture) says the run is over. The trainee's input moves `mouse` (null: an
// external device drives the tool) and takes screenshots (out_dir/screenshot_<n>.png); the run's
// new haptic states go to `scorer`; displacements are coloured from the first frame at or after
// options.settle_s. Throws what the window throws (e.g. a screenshot that cannot be written).
void RunTrainingLoop(LiveRun* live, ViewWindow* window, MouseDevice* mouse,
                     const config::TaskScene& task, const Eigen::Vector3d& start_W_m,
                     const TrainOptions& options, const std::string& out_dir,
                     PalpationScorer* scorer, const std::function<bool()>& run_ended);

}  // namespace hapsim::view
