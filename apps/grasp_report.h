#pragma once
// What `hapsim sim` and `hapsim run` say about the grasper's jaws (tool.grasp, issue 28) at a
// frame: jaws that closed on no point of the body (the grasp region holds no tissue there), and
// points that slipped out (their grip force past tool.grasp.max_force_N).

#include <string>

#include "config/scene.h"
#include "contact/visual_frame.h"

namespace hapsim::apps {

// One line per event of the frame that started at t_s (no trailing newline), or "".
std::string DescribeGraspEvents(const config::Scene& scene, double t_s,
                                const contact::VisualFrameStats& stats);

}  // namespace hapsim::apps
