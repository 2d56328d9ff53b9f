// The window behind a Viewer (viewer.h): its implementation is the viewer module
// (module/viewer_window.cpp, MRPT's gui: ~60 shared libraries of its own, wxWidgets and GTK),
// loaded when the first viewer opens (upd/mrpt_bridge/module.h), so that no other command loads
// them.
#pragma once

#include "upd/nav/viewer.h"

#include <memory>
#include <string>

namespace upd::nav::detail {

class ViewerWindow {
 public:
  virtual ~ViewerWindow();
  virtual MapStyle mapStyle() const = 0;
  virtual bool isOpen() const = 0;
  virtual void setContent(ScoredCloud cloud, MapSnapshot map) = 0;
  virtual void setMap(MapSnapshot map) = 0;
  virtual void pressKey(int key) = 0;
  virtual bool processEvents() = 0;
  virtual void saveScreenshot(const std::string& png) = 0;
};

/// The viewer module's entry point.
struct ViewerModule {
  /// Opens the window (Viewer's constructor); throws std::runtime_error when it fails.
  std::unique_ptr<ViewerWindow> (*open)(const ViewerOptions& options);
};

}  // namespace upd::nav::detail

/// The viewer module's one exported symbol.
extern "C" const upd::nav::detail::ViewerModule upd_nav_viewer_module;
