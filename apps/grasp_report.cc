#include "apps/grasp_report.h"

#include <cstdio>

namespace hapsim::apps {

std::string DescribeGraspEvents(const config::Scene& scene, double t_s,
                                const contact::VisualFrameStats& stats) {
  if (!scene.tool || !scene.tool->grasp) return "";
  const contact::GraspOptions& grasp = *scene.tool->grasp;
  std::string text;
  char line[400];
  if (stats.grasp_closed_now && stats.num_grasp_taken == 0) {
    std::snprintf(line, sizeof(line),
                  "at %.3f s the jaws closed on no point of %s: no free surface node lay "
                  "within tool.grasp.jaw_radius_m = %.4g m of jaw_center_m [%.4g, %.4g, %.4g] "
                  "(tool frame) in %s",
                  t_s, scene.more_bodies.empty() ? scene.body_name.c_str() : "the bodies",
                  grasp.jaw_radius_m, grasp.jaw_center_T_m.x(), grasp.jaw_center_T_m.y(),
                  grasp.jaw_center_T_m.z(), scene.file.c_str());
    text += line;
  }
  if (stats.num_grasp_slipped > 0) {
    std::snprintf(line, sizeof(line),
                  "%sat %.3f s %d grasped point%s slipped out of the jaws (grip force over "
                  "tool.grasp.max_force_N = %.4g N); %d still held",
                  text.empty() ? "" : "\n", t_s, stats.num_grasp_slipped,
                  stats.num_grasp_slipped == 1 ? "" : "s", grasp.max_force_N, stats.num_grasped);
    text += line;
  }
  return text;
}

}  // namespace hapsim::apps
