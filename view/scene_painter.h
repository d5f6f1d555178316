#pragma once
// Draws one instant of a run with OpenCV viz (VTK, rendering off screen: x11_window.h), for `hapsim
// view` and `hapsim train`: the tissue surface coloured by displacement, the rigid objects, the
// tool, the device's ghost, the contact points, the force arrow, palpation targets, and an
// on-screen gauge of the device force and the haptic loop's state. Drawing is a function of a
// ViewState alone, so a picture of a logged run at time t is the picture the live run showed at t.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/viz.hpp>
#include <set>
#include <string>
#include <vector>

#include "config/scene.h"
#include "core/eigen_types.h"
#include "core/tool_shape.h"
#include "fem/surface_embedding.h"
#include "messages/adapters.h"
#include "view/shape_widget.h"

namespace hapsim::view {

// What one picture shows: the newest messages of the run at one instant.
struct ViewState {
  bool has_frame = false;
  hapsim_lcm::sim_frame_t frame;  // body surface, visual tool, contacts
  bool has_haptic = false;
  hapsim_lcm::haptic_state_t haptic;  // device force, the loop's state
  bool has_device = false;
  hapsim_lcm::device_state_t device;  // the device's pose: the ghost
  // Per target of the scene's task (trainer): reached (drawn green) or not (orange).
  std::vector<bool> targets_reached;
  std::string status;  // an extra line under the gauge (the trainer's task), may be empty
};

// Each 0 (the default) is chosen from the scene, so that a 8 mm polyp and a 16 cm liver both
// show their touch: the displacement in the deepest red is 5 mm, or a quarter of the body's
// smallest rest extent if that is less; the gauge's full scale is 1.5 times the task's force
// limit, or the haptic safety limit without a task; the force arrow at full scale is a quarter of
// the scene's size.
struct PainterOptions {
  double displacement_scale_m = 0.0;  // displacement drawn in the deepest red, m
  double force_scale_m_N = 0.0;       // length of the force arrow per newton, m/N
  double force_gauge_N = 0.0;         // full scale of the on-screen gauge, N
  // The view's camera looks from the side, level with the scene's middle, along +y (the second,
  // orthogonal view: depth towards the organ as height on the screen), instead of from the front,
  // above and aside.
  bool side_camera = false;
  // ViewWindow: add the side view as an inset in the picture's top-right corner.
  bool side_view = false;
};

class ScenePainter {
 public:
  // Draws the fixed parts (rigid objects, targets) and points the camera at the scene.
  // rest_positions_m: (3 × N) the body's rest node positions (for the displacement), or empty.
  // visual_surface: the surface the tets carry that is drawn for the body (config::Body), or
  // empty: the frame's boundary triangles are drawn.
  ScenePainter(cv::viz::Viz3d* window, const config::Scene& scene, Matrix3Xd rest_positions_m,
               fem::EmbeddedSurface visual_surface, const PainterOptions& options);

  void Draw(const ViewState& state);
  // Displacements from `frame`'s node positions from now on, instead of from the rest shape: a
  // soft organ that settles under gravity is displaced everywhere, and the touch is what to see.
  void SetDisplacementReference(const hapsim_lcm::sim_frame_t& frame);

 private:
  // The body's surface (the visual one, moved by its weights, or the boundary), smooth-shaded and
  // coloured by displacement; keeps it in body_points_W_m_ for the drop line.
  void DrawBody(const hapsim_lcm::sim_frame_t& frame);
  // The tool's drop line and shadow ring (view/depth_cue.h); returns the gauge's line for it.
  std::string DrawDepthCue(const hapsim_lcm::sim_frame_t& frame);
  // The rigid objects where the frame has them, coloured when selected or grabbed.
  void DrawObjects(const hapsim_lcm::sim_frame_t& frame);
  void DrawGauge(const ViewState& state, const std::string& depth_line);
  // showWidget / removeWidget, remembering what is shown (viz asserts on removing an unknown name).
  void Show(const std::string& name, const cv::viz::Widget& widget,
            const cv::Affine3d& pose = cv::Affine3d::Identity());
  void Hide(const std::string& name);
  // Shows the tool's or the ghost's widget (made once) at `pose`.
  void Place(const std::string& name, const cv::Affine3d& pose);

  cv::viz::Viz3d* window_;
  const config::Scene& scene_;
  Matrix3Xd rest_positions_m_;
  fem::EmbeddedSurface visual_;
  int num_scene_nodes_ = 0;        // the body's nodes: a frame with another count is not drawn
                                   // with visual_ (it is another scene's)
  Eigen::VectorXd visual_rest_m_;  // (3P) the visual surface at the displacement reference
  PainterOptions options_;
  // The body's surface as last drawn (world) and the rigid objects' meshes (own frames), for the
  // drop line; the tool's mesh, for its lowest point.
  Matrix3Xd body_points_W_m_;
  Matrix3Xi body_triangles_;
  std::vector<TriangleMesh> object_meshes_;
  TriangleMesh tool_mesh_;
  std::set<std::string> shown_;
  cv::viz::Widget3D tool_widget_;
  cv::viz::Widget3D ghost_widget_;  // the tool, a little larger (see InflateShape), as lines
};

}  // namespace hapsim::view
