// A screenshot of an X11 window found by its title: what the viewer's window shows, read back
// from the X server (MRPT 2.5's own capture of a CDisplayWindow3D gives black images under
// Xvfb and Mesa).
#pragma once

#include <mrpt/img/CImage.h>

#include <string>

namespace upd::nav::detail {

/// The pixels of the first top-level window titled title on $DISPLAY. Throws
/// std::runtime_error when there is no X display, no such window, or X11 was not built in.
mrpt::img::CImage grabWindow(const std::string& title);

}  // namespace upd::nav::detail
