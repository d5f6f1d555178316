#include "view/view_window.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <stdexcept>

#include "config/body_builder.h"
#include "core/error.h"

namespace hapsim::view {
namespace fs = std::filesystem;
namespace {

// `path` with ".<pid>.tmp" before its extension (the extension tells OpenCV the format).
std::string TemporaryName(const std::string& path) {
  const fs::path target(path);
  return (target.parent_path() / ("." + target.stem().string() + "." + std::to_string(getpid()) +
                                  ".tmp" + target.extension().string()))
      .string();
}

}  // namespace

cv::Size ParseWindowSize(const std::string& text, const std::string& option) {
  int width = 0, height = 0;
  char x = 0, extra = 0;
  if (std::sscanf(text.c_str(), "%d%c%d%c", &width, &x, &height, &extra) != 3 || x != 'x' ||
      width < 64 || height < 64 || width > 8192 || height > 8192)
    throw InputError("", 0, option, "must be WIDTHxHEIGHT, each 64 to 8192, got '" + text + "'");
  return {width, height};
}

ViewWindow::ViewWindow(const std::string& title, const config::Scene& scene, cv::Size size,
                       const PainterOptions& options, bool open_window)
    : renderer_(title + " (renderer)") {
  if (std::getenv("DISPLAY") == nullptr)
    throw std::runtime_error(
        "no X display (DISPLAY is unset): the pictures are rendered with "
        "OpenGL on one; for headless use run under Xvfb, e.g. xvfb-run -a");
  renderer_.setOffScreenRendering();
  renderer_.setWindowSize(size);
  const std::optional<config::Body> body = config::MakeSceneBody(scene);
  const Matrix3Xd rest_m = body ? body->model.mesh.rest_positions_m : Matrix3Xd();
  const fem::EmbeddedSurface visual = body ? body->visual_surface : fem::EmbeddedSurface();
  painter_ = std::make_unique<ScenePainter>(&renderer_, scene, rest_m, visual, options);
  if (options.side_view) {
    side_renderer_ = std::make_unique<cv::viz::Viz3d>(title + " (side renderer)");
    side_renderer_->setOffScreenRendering();
    side_renderer_->setWindowSize(
        cv::Size(std::max(size.width / 3, 64), std::max(size.height / 3, 64)));
    PainterOptions side = options;
    side.side_camera = true;
    side_painter_ =
        std::make_unique<ScenePainter>(side_renderer_.get(), scene, rest_m, visual, side);
  }
  if (open_window) window_ = std::make_unique<X11Window>(title, size);
}

const cv::Mat& ViewWindow::Show(const ViewState& state) {
  painter_->Draw(state);
  picture_ = renderer_.getScreenshot();  // renders
  if (side_painter_) {
    // The side view (no gauge of its own), framed, in the top-right corner.
    side_painter_->Draw(state);
    const cv::Mat side = side_renderer_->getScreenshot();
    const int width = std::min(side.cols, picture_.cols),
              height = std::min(side.rows, picture_.rows);
    const cv::Rect inset(picture_.cols - width, 0, width, height);
    side(cv::Rect(0, 0, width, height)).copyTo(picture_(inset));
    cv::rectangle(picture_, inset, cv::Scalar(200, 200, 200), 1);
    cv::putText(picture_, "side", inset.tl() + cv::Point(6, 16), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                cv::Scalar(220, 220, 220), 1, cv::LINE_AA);
  }
  if (window_) window_->Show(picture_);
  return picture_;
}

std::vector<WindowEvent> ViewWindow::Poll() {
  return window_ ? window_->Poll() : std::vector<WindowEvent>();
}

void ViewWindow::SaveScreenshot(const std::string& path) const {
  const std::string temp = TemporaryName(path);
  if (picture_.empty() || !cv::imwrite(temp, picture_)) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw std::runtime_error("cannot write the screenshot " + path);
  }
  fs::rename(temp, path);
}

void ViewWindow::AddVideoFrame(const std::string& path, double fps) {
  if (!video_.isOpened()) {
    video_path_ = path;
    video_temp_path_ = TemporaryName(path);
    if (!video_.open(video_temp_path_, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps,
                     picture_.size()))
      throw std::runtime_error("cannot write the video " + path);
  }
  video_.write(picture_);
}

void ViewWindow::FinishVideo() {
  if (!video_.isOpened()) return;
  video_.release();
  fs::rename(video_temp_path_, video_path_);
}

}  // namespace hapsim::view
