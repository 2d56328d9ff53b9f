// What the navigation loop keeps of one depth frame: the frame scored by upd::FrameScorer
// (upd/core/frame_scorer.h) in the world frame, with the obstacle detector selectable (the UPD
// or the roughness-index baseline, which reads a smooth 20 deg ramp as an obstacle), and the
// world xy of its NonTraversable points as the navigator's current-frame obstacles.
#pragma once

#include "upd/core/frame_scorer.h"

namespace upd::nav {

using upd::core::ObstacleDetector;
using upd::core::parseObstacleDetector;
using upd::core::toString;

/// A scored frame in the world frame (obstacles_world filled; its wall time in timings.total_ms).
using FrameEvidence = core::ScoredFrame;

}  // namespace upd::nav
