#pragma once
// A plain X11 window that shows pictures and reports the keyboard and the mouse, for the viewer
// and the trainer. The pictures are rendered by OpenCV viz (VTK) off screen.
//
// Why not viz's own window: its event loop (Viz3d::spinOnce) is broken with VTK 9.1, Debian 12's:
// the window takes no key or mouse event and X errors (BadWindow) end the process
// (opencv_contrib issue #3102; seen here). OpenCV's highgui (Qt backend) delivered keys but no
// mouse events under Xvfb. Xlib itself is a dozen calls.

#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace hapsim::view {

struct WindowEvent {
  enum class Type { kKey, kMouseMove, kButtonDown, kButtonUp, kWheelUp, kWheelDown };
  Type type = Type::kKey;
  std::string key;   // kKey: the X key name ("space", "q", "Up", "Page_Up", "period")
  int x = 0, y = 0;  // pointer position in the window, pixels
  int button = 0;    // kButtonDown/Up: 1 left, 2 middle, 3 right
};

class X11Window {
 public:
  // Opens a window of `size` on $DISPLAY titled `title`. Throws std::runtime_error without a
  // display (the message says to use Xvfb for headless runs).
  X11Window(const std::string& title, cv::Size size);
  ~X11Window();
  X11Window(const X11Window&) = delete;
  X11Window& operator=(const X11Window&) = delete;

  // Shows a BGR picture of the window's size.
  void Show(const cv::Mat& bgr);
  // The events since the last call (keys, pointer, buttons, wheel); sets closed() when the
  // window manager asks to close it.
  std::vector<WindowEvent> Poll();
  bool closed() const { return closed_; }
  cv::Size size() const { return size_; }

 private:
  struct Xlib;  // Xlib's handles, kept out of this header: Xlib.h defines macros such as Status
  std::unique_ptr<Xlib> x_;
  cv::Size size_;
  std::vector<char> pixels_;  // the picture as 32-bit BGRX, the layout of 24-bit TrueColor
  bool closed_ = false;
};

}  // namespace hapsim::view
