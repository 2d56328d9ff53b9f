// A map snapshot as MRPT objects (map_view.h): shared by the map figure and the viewer.
#pragma once

#include "upd/nav/map_view.h"

#include <mrpt/opengl/CSetOfObjects.h>

namespace upd::nav::detail {

/// The map in style coloured by mode (height over [z_lo, z_hi]), the path as a dark line and
/// the robot as an orange box at the path's end, heading along its last segment.
mrpt::opengl::CSetOfObjects::Ptr mapObjects(const MapSnapshot& map, MapStyle style, FigureColor mode,
                                            float z_lo, float z_hi);

}  // namespace upd::nav::detail
