// Reading a window's pixels from the X server (window_grab.h).
#include "window_grab.h"

#include <stdexcept>

#ifdef UPD_HAVE_X11
#include <X11/Xlib.h>
#include <X11/Xutil.h>

#include <algorithm>
#include <memory>
#endif

namespace upd::nav::detail {

#ifdef UPD_HAVE_X11
namespace {

// Depth-first over the window tree: the first window whose WM_NAME is title.
Window findByTitle(Display* dpy, Window w, const std::string& title) {
  char* name = nullptr;
  if (XFetchName(dpy, w, &name) && name != nullptr) {
    const bool match = title == name;
    XFree(name);
    if (match) return w;
  }
  Window root = 0, parent = 0, *children = nullptr;
  unsigned int n = 0;
  if (!XQueryTree(dpy, w, &root, &parent, &children, &n)) return 0;
  Window found = 0;
  for (unsigned int i = 0; i < n && found == 0; ++i) found = findByTitle(dpy, children[i], title);
  if (children != nullptr) XFree(children);
  return found;
}

int shiftOf(unsigned long mask) {
  int s = 0;
  while (mask != 0 && (mask & 1) == 0) mask >>= 1, ++s;
  return s;
}

}  // namespace

mrpt::img::CImage grabWindow(const std::string& title) {
  std::unique_ptr<Display, int (*)(Display*)> dpy(XOpenDisplay(nullptr), XCloseDisplay);
  if (!dpy) throw std::runtime_error("cannot open the X display to take a screenshot");
  const Window w = findByTitle(dpy.get(), DefaultRootWindow(dpy.get()), title);
  if (w == 0) throw std::runtime_error("no window titled '" + title + "' to take a screenshot of");
  XWindowAttributes attr;
  if (!XGetWindowAttributes(dpy.get(), w, &attr) || attr.width <= 0 || attr.height <= 0) {
    throw std::runtime_error("the window '" + title + "' has no size");
  }
  // X gives the pixels of the part of a window that is on the screen only: a window larger than
  // the screen (a small virtual display) is grabbed clipped to it.
  int rx = 0, ry = 0;
  Window child = 0;
  XTranslateCoordinates(dpy.get(), w, attr.root, 0, 0, &rx, &ry, &child);
  XWindowAttributes root_attr;
  XGetWindowAttributes(dpy.get(), attr.root, &root_attr);
  const int x0 = std::max(0, -rx), y0 = std::max(0, -ry);
  const int width = std::min(attr.width, root_attr.width - rx) - x0;
  const int height = std::min(attr.height, root_attr.height - ry) - y0;
  if (width <= 0 || height <= 0) {
    throw std::runtime_error("the window '" + title + "' is outside the screen");
  }
  XImage* xi = XGetImage(dpy.get(), w, x0, y0, unsigned(width), unsigned(height), AllPlanes,
                         ZPixmap);
  if (xi == nullptr) {
    throw std::runtime_error("the X server gave no image of the window '" + title + "'");
  }
  const int rs = shiftOf(xi->red_mask), gs = shiftOf(xi->green_mask), bs = shiftOf(xi->blue_mask);
  mrpt::img::CImage img(width, height, mrpt::img::CH_RGB);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const unsigned long p = XGetPixel(xi, x, y);
      img.setPixel(x, y,
                   mrpt::img::TColor(std::uint8_t((p & xi->red_mask) >> rs),
                                     std::uint8_t((p & xi->green_mask) >> gs),
                                     std::uint8_t((p & xi->blue_mask) >> bs)));
    }
  }
  XDestroyImage(xi);
  return img;
}

#else

mrpt::img::CImage grabWindow(const std::string&) {
  throw std::runtime_error("screenshots need X11 (libx11-dev), which this build did not find");
}

#endif

}  // namespace upd::nav::detail
