#pragma once
// What `hapsim view` shows (apps/view_command.cc parses its options, reads the log or waits for
// the live run, and loads the run's scene): a logged run played in a window driven by keys, or
// written as a screenshot, a video or the task's score; a live run shown as it comes, or a
// screenshot or a video of it.

#include <string>

#include "config/scene.h"
#include "messages/channels.h"
#include "view/live_run.h"
#include "view/run_timeline.h"
#include "view/scene_painter.h"

namespace hapsim::view {

// `hapsim view`'s options (apps/view_command.cc binds them to the command line).
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

// Shows the logged run `run` (read from options.log_path) drawn with `scene`: writes the task's
// score (--score), a screenshot or a video and returns, or plays it in a window until q, Escape
// or the window is closed.
void PlayLoggedRun(const LoggedRun& run, const config::Scene& scene, const ViewOptions& options);

// Shows the run `live` hears (its RUN_INFO has come; `scene` is the run's) drawn with `scene`:
// writes a screenshot and returns, or shows it in a window (recording a video with --video)
// until q, Escape, the window is closed or, for a video, the run ends (5 s without its
// processes) or --duration has passed. The caller's ReceiveThread fills the run meanwhile.
void ShowLiveRun(LiveRun* live, const config::Scene& scene, const ViewOptions& options);

}  // namespace hapsim::view
