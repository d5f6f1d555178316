#pragma once
// The pictures of `hapsim view` and `hapsim train`: OpenCV viz (VTK) renders them off screen
// (ScenePainter), an X11Window shows them and takes the keyboard and mouse, and they can go to a
// PNG screenshot or an AVI video, each written under a temporary name and renamed when complete.
// Rendering needs an X display even off screen (VTK's OpenGL context): Xvfb for headless use.

#include <memory>
#include <opencv2/videoio.hpp>
#include <opencv2/viz.hpp>
#include <string>
#include <vector>

#include "config/scene.h"
#include "view/scene_painter.h"
#include "view/x11_window.h"

namespace hapsim::view {

// Parses "WIDTHxHEIGHT" (e.g. 1024x768); throws InputError naming `option` otherwise.
cv::Size ParseWindowSize(const std::string& text, const std::string& option);

class ViewWindow {
 public:
  // Sets up the renderer at `size` and draws the scene's fixed parts; opens a window titled
  // `title` when `open_window` (an interactive view; screenshots and videos need none). The
  // body's rest positions and visual surface come from building the scene's deformable objects.
  // With options.side_view a second renderer draws the scene from the side, shown as an inset a
  // third of the picture's size in its top-right corner. `scene` must outlive the view.
  ViewWindow(const std::string& title, const config::Scene& scene, cv::Size size,
             const PainterOptions& options, bool open_window);

  // Renders `state`, shows it in the window (if open) and returns the picture (BGR).
  const cv::Mat& Show(const ViewState& state);
  // Colour displacements from this frame's shape (ScenePainter::SetDisplacementReference).
  void SetDisplacementReference(const hapsim_lcm::sim_frame_t& frame) {
    painter_->SetDisplacementReference(frame);
    if (side_painter_) side_painter_->SetDisplacementReference(frame);
  }
  // The window's events since the last call; none without a window.
  std::vector<WindowEvent> Poll();
  bool closed() const { return window_ && window_->closed(); }
  cv::viz::Viz3d& renderer() { return renderer_; }

  // The last picture to a PNG file (atomically). Throws std::runtime_error when it cannot be
  // written.
  void SaveScreenshot(const std::string& path) const;
  // Appends the last picture to the video `path` (MJPG AVI at `fps`), opened on the first call
  // and completed (renamed into place) by FinishVideo.
  void AddVideoFrame(const std::string& path, double fps);
  void FinishVideo();

 private:
  cv::viz::Viz3d renderer_;
  std::unique_ptr<ScenePainter> painter_;
  std::unique_ptr<cv::viz::Viz3d> side_renderer_;  // with options.side_view
  std::unique_ptr<ScenePainter> side_painter_;
  std::unique_ptr<X11Window> window_;
  cv::Mat picture_;
  cv::VideoWriter video_;
  std::string video_path_, video_temp_path_;
};

}  // namespace hapsim::view
