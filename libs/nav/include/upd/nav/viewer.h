// The interactive 3D viewer of `upd view` and `upd playback --view`: an MRPT CDisplayWindow3D
// with a scored cloud, a traversability map (map_view.h), the robot and its path, coloured by
// the figures' colour maps (figure.h) with the colour bar at the right and the keys in the
// window:
//   z l c s h (or 1-5)  colour by zeta, label, cost, slope, height
//   n                   normals on / off
//   m                   map: grid cells, octree voxels, none
//   r                   reset the view          p  save a screenshot (upd-view-NNN.png)
//   t                   help text on / off      q or Esc  close
// The mouse turns (left), zooms (wheel) and pans (right / Shift) as in every MRPT window.
#pragma once

#include "upd/core/frame_scorer.h"
#include "upd/nav/figure.h"
#include "upd/nav/map_view.h"

#include <Eigen/Core>

#include <memory>
#include <string>

namespace upd::nav {

/// True when a window can be opened ($DISPLAY or $WAYLAND_DISPLAY is set).
bool displayAvailable();

/// The valid points of a scored frame (world frame) as the viewer and the figures draw them.
ScoredCloud scoredCloudOf(const core::ScoredFrame& frame);

struct ViewerOptions {
  FigureColor color = FigureColor::Zeta;
  bool normals = false;
  MapStyle map = MapStyle::Grid;
  Eigen::Vector3f up{0, 0, 1};     ///< a cloud's up vector (drawn upright)
  int width = 1280, height = 900;  ///< of the window [px], colour bar included
  std::string title = "upd view";
  std::string screenshot_prefix = "upd-view";  ///< key p writes PREFIX-NNN.png
  /// The camera follows the robot (the path's end) at every update, 12 m away at first
  /// (playback); the mouse still turns and zooms.
  bool follow_robot = false;
};

class Viewer {
 public:
  /// Opens the window; throws std::runtime_error when there is no display or it fails.
  explicit Viewer(const ViewerOptions& options);
  ~Viewer();
  Viewer(const Viewer&) = delete;
  Viewer& operator=(const Viewer&) = delete;

  /// The map style shown now (the m key changes it).
  MapStyle mapStyle() const;
  /// False once the window was closed (by the user, q or Esc).
  bool isOpen() const;
  /// Replaces what is drawn and redraws; the first content sets the camera to see it all.
  void setContent(ScoredCloud cloud, MapSnapshot map);
  void setMap(MapSnapshot map);
  /// Handles the keys pressed since the last call. False once the window is closed.
  bool processEvents();
  /// Acts on one key as if it was pressed (the keys of the header comment).
  void pressKey(int key);
  /// Waits for the window to show the current content and writes it to png (atomically).
  /// Throws std::runtime_error when no image comes within a few seconds.
  void saveScreenshot(const std::string& png);
  /// Processes events until the window is closed.
  void runUntilClosed();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Ends the process with code, without running static destructors, when a Viewer was opened
/// (else returns): MRPT 2.5's wx thread goes on painting a closed CDisplayWindow3D while the
/// libraries' static objects are destroyed, a crash at exit seen under Xvfb. Flushes stdout
/// and stderr first. `upd` calls it when a command returns.
void exitIfViewerShown(int code);

}  // namespace upd::nav
