#include "view/x11_window.h"

#include <X11/Xlib.h>
#include <X11/Xutil.h>

#include <stdexcept>

namespace hapsim::view {

struct X11Window::Xlib {
  Display* display = nullptr;
  Window window = 0;
  GC gc = nullptr;
  Atom delete_atom = 0;
  XImage* image = nullptr;
};

X11Window::X11Window(const std::string& title, cv::Size size)
    : x_(std::make_unique<Xlib>()), size_(size) {
  Display* display = x_->display = XOpenDisplay(nullptr);
  if (display == nullptr)
    throw std::runtime_error(
        "cannot open the X display (DISPLAY is unset or unreachable); for headless use run "
        "under Xvfb, e.g. xvfb-run -a hapsim ...");
  const int screen = DefaultScreen(display);
  Visual* visual = DefaultVisual(display, screen);
  if (DefaultDepth(display, screen) != 24 || visual->c_class != TrueColor) {
    XCloseDisplay(display);
    throw std::runtime_error(
        "the X display is not 24-bit TrueColor (start Xvfb with -screen 0 "
        "1280x1024x24)");
  }
  const Window window = x_->window =
      XCreateSimpleWindow(display, RootWindow(display, screen), 0, 0, size.width, size.height, 0,
                          BlackPixel(display, screen), BlackPixel(display, screen));
  XStoreName(display, window, title.c_str());
  // Fixed size: the pictures are rendered at it.
  XSizeHints hints{};
  hints.flags = PMinSize | PMaxSize;
  hints.min_width = hints.max_width = size.width;
  hints.min_height = hints.max_height = size.height;
  XSetWMNormalHints(display, window, &hints);
  XSelectInput(display, window,
               KeyPressMask | PointerMotionMask | ButtonPressMask | ButtonReleaseMask |
                   ExposureMask | StructureNotifyMask);
  x_->delete_atom = XInternAtom(display, "WM_DELETE_WINDOW", False);
  XSetWMProtocols(display, window, &x_->delete_atom, 1);
  x_->gc = XCreateGC(display, window, 0, nullptr);
  pixels_.resize(static_cast<size_t>(4) * size.width * size.height);
  x_->image =
      XCreateImage(display, visual, 24, ZPixmap, 0, pixels_.data(), size.width, size.height, 32, 0);
  XMapWindow(display, window);
  XFlush(display);
}

X11Window::~X11Window() {
  if (x_->image != nullptr) {
    x_->image->data = nullptr;  // the pixels belong to pixels_
    XDestroyImage(x_->image);
  }
  if (x_->gc != nullptr) XFreeGC(x_->display, x_->gc);
  if (x_->window != 0) XDestroyWindow(x_->display, x_->window);
  if (x_->display != nullptr) XCloseDisplay(x_->display);
}

void X11Window::Show(const cv::Mat& bgr) {
  if (closed_) return;  // drawing into a destroyed window is an X error that ends the process
  if (bgr.size() != size_ || bgr.type() != CV_8UC3)
    throw std::invalid_argument("X11Window::Show: a BGR picture of the window's size is needed");
  for (int y = 0; y < size_.height; ++y) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(y);
    char* out = pixels_.data() + static_cast<size_t>(4) * size_.width * y;
    for (int x = 0; x < size_.width; ++x) {
      out[4 * x + 0] = static_cast<char>(row[x][0]);  // blue
      out[4 * x + 1] = static_cast<char>(row[x][1]);  // green
      out[4 * x + 2] = static_cast<char>(row[x][2]);  // red
      out[4 * x + 3] = 0;
    }
  }
  XPutImage(x_->display, x_->window, x_->gc, x_->image, 0, 0, 0, 0, size_.width, size_.height);
  XFlush(x_->display);
}

std::vector<WindowEvent> X11Window::Poll() {
  std::vector<WindowEvent> events;
  while (XPending(x_->display) > 0) {
    XEvent x_event;
    XNextEvent(x_->display, &x_event);
    WindowEvent event;
    switch (x_event.type) {
      case KeyPress: {
        const KeySym symbol = XLookupKeysym(&x_event.xkey, 0);
        const char* name = XKeysymToString(symbol);
        if (name == nullptr) break;
        event.type = WindowEvent::Type::kKey;
        event.key = name;
        event.x = x_event.xkey.x;
        event.y = x_event.xkey.y;
        events.push_back(event);
        break;
      }
      case MotionNotify:
        event.type = WindowEvent::Type::kMouseMove;
        event.x = x_event.xmotion.x;
        event.y = x_event.xmotion.y;
        events.push_back(event);
        break;
      case ButtonPress:
      case ButtonRelease: {
        const unsigned button = x_event.xbutton.button;
        event.x = x_event.xbutton.x;
        event.y = x_event.xbutton.y;
        if (button == Button4 || button == Button5) {  // the wheel: a press per notch
          if (x_event.type == ButtonRelease) break;
          event.type =
              button == Button4 ? WindowEvent::Type::kWheelUp : WindowEvent::Type::kWheelDown;
        } else {
          event.type = x_event.type == ButtonPress ? WindowEvent::Type::kButtonDown
                                                   : WindowEvent::Type::kButtonUp;
          event.button = static_cast<int>(button);
        }
        events.push_back(event);
        break;
      }
      case ClientMessage:
        if (static_cast<Atom>(x_event.xclient.data.l[0]) == x_->delete_atom) closed_ = true;
        break;
      case DestroyNotify:
        closed_ = true;
        break;
      default:
        break;  // Expose: the next Show repaints
    }
  }
  return events;
}

}  // namespace hapsim::view
